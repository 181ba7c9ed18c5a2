"""Figures of a sweep (``experiments.sweep``): one PNG per measure.

One swept value: the measure against it, a line with the 95 % intervals as error bars. Two:
a heatmap over the grid, each cell labelled with its value and its number of trials. More
than two: no figure (the table has every point).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from comgrasp_pin.experiments.report.common import load_pyplot


def _line(ax, table, path: str, measure: str) -> None:
    x = np.array([point[path] for point, _ in table])
    value, lo, hi = (np.array([m[measure][i] for _, m in table], float) for i in range(3))
    # (clipped: a Wilson interval of 100 % ends at 100 % less a rounding error)
    lower = np.clip(np.where(np.isfinite(lo), value - lo, 0.0), 0.0, None)
    upper = np.clip(np.where(np.isfinite(hi), hi - value, 0.0), 0.0, None)
    ax.errorbar(x, value, yerr=[lower, upper], fmt="o-", capsize=4)
    ax.set_xlabel(path)
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.grid(alpha=0.3)


def _heatmap(fig, ax, table, paths: list[str], measure: str) -> None:
    rows = sorted({point[paths[0]] for point, _ in table})
    cols = sorted({point[paths[1]] for point, _ in table})
    grid = np.full((len(rows), len(cols)), np.nan)
    counts = np.zeros_like(grid, int)
    for point, m in table:
        i, j = rows.index(point[paths[0]]), cols.index(point[paths[1]])
        grid[i, j], counts[i, j] = m[measure][0], m[measure][3]
    image = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
    fig.colorbar(image, ax=ax)
    for i in range(len(rows)):
        for j in range(len(cols)):
            finite = math.isfinite(grid[i, j])
            text = f"{grid[i, j]:.1f}" if finite else "–"
            light = finite and float(image.norm(grid[i, j])) > 0.5  # viridis: yellow on top
            ax.text(j, i, f"{text}\nn={counts[i, j]}", ha="center", va="center", fontsize=8,
                    color="k" if light else "w")  # fmt: skip
    ax.set_xticks(range(len(cols)), [f"{c:g}" for c in cols])
    ax.set_yticks(range(len(rows)), [f"{r:g}" for r in rows])
    ax.set_xlabel(paths[1])
    ax.set_ylabel(paths[0])


def sweep_figures(table, params, out: Path, measures: dict[str, str]) -> list[Path]:
    """``sweep_<measure>.png`` in ``out`` for each of ``measures`` (name: label, the sweep's
    ``MEASURES``); none for more than two params."""
    paths = [path for path, _ in params]
    if len(paths) > 2:
        return []
    plt = load_pyplot()
    written = []
    for measure, label in measures.items():
        fig, ax = plt.subplots(figsize=(6, 4.5))
        if len(paths) == 1:
            _line(ax, table, paths[0], measure)
            ax.set_ylabel(label)
        else:
            _heatmap(fig, ax, table, paths, measure)
        ax.set_title(label)
        fig.tight_layout()
        path = out / f"sweep_{measure}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written
