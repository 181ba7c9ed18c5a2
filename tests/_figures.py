"""What a figure draws, for the report's figure tests (issue 33, item 7).

The report's figure functions write a PNG and close their figure; ``saved_figures`` keeps
every Figure saved from then on in the test (matplotlib's ``Figure.savefig`` wrapped through
the test's ``monkeypatch``), so a test reads its axes, labels, lines and bars, not the file's
size.
"""

from __future__ import annotations

import numpy as np
from matplotlib.container import BarContainer, ErrorbarContainer
from matplotlib.figure import Figure


def saved_figures(monkeypatch) -> list:
    """A list that receives the Figures saved from now on in the test, in order (each with
    ``.saved_to``, the path it was saved to)."""
    saved = []
    original = Figure.savefig

    def savefig(self, fname, *args, **kwargs):
        self.saved_to = fname
        saved.append(self)
        return original(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return saved


def axes_labelled(fig: Figure, ylabel: str) -> list:
    """The figure's visible axes (subfigures' included) whose y label starts with ``ylabel``."""
    return [ax for ax in fig.axes if ax.get_visible() and ax.get_ylabel().startswith(ylabel)]


def bars(ax) -> list[tuple[float, float]]:
    """(x centre, height) of every bar the axes draws, left to right."""
    out = [
        (p.get_x() + p.get_width() / 2, p.get_height())
        for c in ax.containers
        if isinstance(c, BarContainer)
        for p in c
    ]
    return sorted(out)


def error_bar_data(ax) -> list[tuple[np.ndarray, np.ndarray]]:
    """(x, y) of each ``errorbar`` series that draws its points (not ``fmt="none"``)."""
    out = []
    for c in ax.containers:
        if isinstance(c, ErrorbarContainer) and c.lines[0] is not None:
            line = c.lines[0]
            out.append((np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)))
    return out


def error_bar_segments(ax) -> list[np.ndarray]:
    """(2, 2) end points of every error bar drawn by ``errorbar`` on the axes."""
    return [
        np.asarray(seg)
        for c in ax.containers
        if isinstance(c, ErrorbarContainer)
        for collection in c.lines[2]
        for seg in collection.get_segments()
    ]


def has_line_with(ax, y, atol: float = 1e-9) -> bool:
    """Whether one of the axes' lines draws exactly ``y`` (nan where a gap is expected)."""
    y = np.asarray(y, float)
    for line in ax.lines:
        drawn = np.asarray(line.get_ydata(), float)
        if drawn.shape == y.shape and np.allclose(drawn, y, atol=atol, equal_nan=True):
            return True
    return False


def texts(fig: Figure) -> list[str]:
    """Every text the figure draws: on its axes, titles, labels, legends, suptitles."""
    return [t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")) if t.get_text()]
