"""The calibration section: z = (pos_esti - pos_real) / pos_std against N(0, 1)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from comgrasp_pin.experiments.report.common import (
    N01_COV68,
    NOT_RECORDED,
    TARGET_COV95_BIN,
    TARGET_COV95_OVERALL,
    TARGET_RMS_Z,
    abs_tilts,
    bin_label,
    column_values,
    objects_in,
    percent,
    recorded,
    rows_of,
    without_errors,
)
from comgrasp_pin.experiments.stats import (
    CALIBRATION_BINS_DEG,
    binned_calibration,
    calibration,
    wilson_interval,
    z_scores,
)


def calibration_z(rows: Sequence[dict]) -> np.ndarray:
    """z = (pos_esti_m − pos_real_m) / pos_std_m per grasp (nan where no std is recorded)."""
    return z_scores(
        column_values(rows, "pos_esti_m"),
        column_values(rows, "pos_real_m"),
        column_values(rows, "pos_std_m"),
    )


def _calibration_diagnosis(c) -> str:
    """One sentence on what the overall numbers say about the stated std, or ""."""
    lo95, hi95 = TARGET_COV95_OVERALL
    if not c.n:
        return ""
    if abs(c.mean) > 0.5:
        return (
            f" The mean z of {c.mean:+.2f} says the estimate is biased by about "
            f"{abs(c.mean):.1f} stated std."
        )
    if c.cov95 < lo95:
        return " Too few inside: the stated std is too small for these misses."
    if c.cov95 > hi95 and c.rms < TARGET_RMS_Z[0]:
        return " Too many inside and rms z below 1: the stated std is too large (cautious)."
    if c.rms > TARGET_RMS_Z[1]:
        return (
            " Coverage near its target with an rms z above 1: a few misses far out (heavy tails)."
        )
    return ""


def _cov_cell(inside: int, n: int) -> str:
    if not n:
        return "–"
    lo, hi = wilson_interval(inside, n)
    return f"{100 * inside / n:.1f} % ({100 * lo:.0f}–{100 * hi:.0f})"


def calibration_table(
    rows: Sequence[dict], objects: Sequence[str] | None = None, edges=CALIBRATION_BINS_DEG
) -> str:
    """Markdown: z = (pos_esti − pos_real) / pos_std against N(0, 1) per |θ| bin and
    overall: n, the share inside ±1σ (68 %) and ±1.96σ (95 %) with Wilson intervals, rms
    and mean z, and the targets (95 %: 93–97 % overall and ≥ 90 % per bin; rms z 0.9–1.1)."""
    ok = without_errors(rows)
    objects = objects_in(ok, objects)
    sel = rows_of(ok, objects)
    if not recorded(sel, "pos_std_m"):
        return f"Calibration: `pos_std_m` {NOT_RECORDED} in these rows; no calibration."
    z, theta = calibration_z(sel), abs_tilts(sel)
    lines = [
        f"Objects {', '.join(objects)}. z = (pos_esti − pos_real) / pos_std; N(0, 1) has "
        f"{100 * N01_COV68:.1f} % inside ±1σ, 95 % inside ±1.96σ and rms 1. In brackets: "
        "95 % Wilson interval of the coverage.",
        "",
        "| tilt bin (deg) | n | coverage ±1σ (68 %) | coverage ±1.96σ (95 %) | rms z | mean z "
        "| target |",
        "|---|---|---|---|---|---|---|",
    ]
    short = []
    for lo, hi, c in binned_calibration(theta, z, edges):
        if not c.n:
            lines.append(f"| {bin_label(lo, hi)} | 0 | – | – | – | – | – |")
            continue
        ok_bin = c.cov95 >= TARGET_COV95_BIN
        verdict = "met"
        if not ok_bin:
            short.append(f"{bin_label(lo, hi)}° ({percent(c.cov95)}, n {c.n})")
            # a bin whose Wilson interval still reaches the target may be short by chance
            reaches = wilson_interval(c.inside95, c.n)[1] >= TARGET_COV95_BIN
            verdict = "not met (interval reaches it)" if reaches else "not met"
        lines.append(
            f"| {bin_label(lo, hi)} | {c.n} | {_cov_cell(c.inside68, c.n)} | "
            f"{_cov_cell(c.inside95, c.n)} | {c.rms:.2f} | {c.mean:+.2f} | "
            f"95 % ≥ {100 * TARGET_COV95_BIN:.0f} %: {verdict} |"
        )
    c = calibration(z)
    lo95, hi95 = TARGET_COV95_OVERALL
    met95 = lo95 <= c.cov95 <= hi95
    met_rms = TARGET_RMS_Z[0] <= c.rms <= TARGET_RMS_Z[1]
    lines.append(
        f"| **all** | {c.n} | {_cov_cell(c.inside68, c.n)} | {_cov_cell(c.inside95, c.n)} | "
        f"{c.rms:.2f} | {c.mean:+.2f} | 95 % in {100 * lo95:.0f}–{100 * hi95:.0f} %: "
        f"{'met' if met95 else 'not met'}; rms z in {TARGET_RMS_Z[0]:g}–{TARGET_RMS_Z[1]:g}: "
        f"{'met' if met_rms else 'not met'} |"
    )
    missing = int(np.sum(~np.isfinite(z)))
    lines += [
        "",
        f"Targets: 95 % coverage {100 * lo95:.0f}–{100 * hi95:.0f} % overall "
        f"({'met' if met95 else 'not met'}: {percent(c.cov95)}) and ≥ "
        f"{100 * TARGET_COV95_BIN:.0f} % in every bin "
        f"({'not met at ' + ', '.join(short) if short else 'met'}); rms z "
        f"{TARGET_RMS_Z[0]:g}–{TARGET_RMS_Z[1]:g} ({'met' if met_rms else 'not met'}: "
        f"{c.rms:.2f})."
        + _calibration_diagnosis(c)
        + (f" {missing} grasp(s) without a recorded std are left out." if missing else ""),
    ]
    return "\n".join(lines)
