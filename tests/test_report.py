"""Report tables and figures from known rows."""

import math

import numpy as np
import pytest
from _figures import (
    axes_labelled,
    bars,
    error_bar_data,
    error_bar_segments,
    has_line_with,
    saved_figures,
    texts,
)

from comgrasp_pin.experiments import paper, report
from comgrasp_pin.experiments.report import (
    accuracy_figure,
    accuracy_plot,
    accuracy_table,
    accuracy_tables,
    calibration_figure,
    calibration_table,
    common,
    extra_pose_summary,
    method_comparison,
    regrasp_figure,
    regrasp_table,
    success_rates,
)


def _regrasp_rows():
    rows = []
    for k in range(10):
        rows.append({"object": "obj1", "trial": k, "method": "baseline", "success": int(k < 7)})
        rows.append({"object": "obj1", "trial": k, "method": "regrasp", "success": int(k < 9)})
    rows.append(
        {"object": "obj1", "trial": 10, "method": "regrasp", "success": "", "error": "boom"}
    )
    return rows


def _check_regrasp_figure(fig, rows) -> None:
    """One axes of success rates: a bar per object and method at 100 s / n, counted here from
    the rows (an error is a failure), on the bars "s/n", the paper's values as diamonds."""
    (ax,) = axes_labelled(fig, "pick-and-place success (%)")
    objects = sorted({r["object"] for r in rows}, key=lambda o: int(o[3:]))
    assert [t.get_text() for t in ax.get_xticklabels()] == objects
    expected = []
    for obj in objects:
        for method in ("baseline", "regrasp"):  # left, right
            trials = [r for r in rows if r["object"] == obj and r["method"] == method]
            s = sum(1 for r in trials if not r.get("error") and r["success"] == 1)
            expected.append(100 * s / len(trials))
            assert f"{s}/{len(trials)}" in [t.get_text() for t in ax.texts]
            if obj in paper.SUCCESS_PERCENT:
                value = paper.SUCCESS_PERCENT[obj][0 if method == "regrasp" else 1]
                assert has_line_with(ax, [value])
    assert [h for _, h in bars(ax)] == pytest.approx(expected)


def test_figures_leave_the_callers_backend_alone(tmp_path, monkeypatch):
    """A notebook's inline backend stays on after a report figure is written (it used to be
    switched to Agg, and the notebook's later figures never showed)."""
    figures = saved_figures(monkeypatch)
    import matplotlib
    import matplotlib.pyplot as plt

    before = matplotlib.get_backend()
    plt.switch_backend("svg")
    try:
        regrasp_figure(_regrasp_rows(), tmp_path / "r.png")
        assert matplotlib.get_backend() == "svg"
        (fig,) = figures
        assert fig.saved_to == tmp_path / "r.png" and (tmp_path / "r.png").is_file()
        _check_regrasp_figure(fig, _regrasp_rows())  # 70 % (7/10) and 81.8 % (9/11)
    finally:
        plt.switch_backend(before)


def test_success_rates_count_errors_as_failures():
    rates = success_rates(_regrasp_rows())
    assert rates[("obj1", "baseline")] == (7, 10)
    assert rates[("obj1", "regrasp")] == (9, 11)


def _bin_means(rows, column, edges) -> np.ndarray:
    """Mean of 100 * ``column`` per |theta_deg| bin, nan where a bin is empty (by hand)."""
    theta = np.abs([r["theta_deg"] for r in rows])
    values = 100 * np.array([r[column] for r in rows])
    k = np.searchsorted(edges, theta, side="right") - 1
    return np.array([values[k == i].mean() if np.any(k == i) else np.nan
                     for i in range(len(edges) - 1)])  # fmt: skip


def _check_accuracy_panel(fig, rows, obj) -> None:
    """The object's panel draws ours and the paper's method in our world as bin means."""
    from comgrasp_pin.experiments.stats import THETA_BINS_DEG

    (ax,) = [ax for ax in fig.axes if ax.get_title(loc="left").startswith(obj)]
    mine = [r for r in rows if r["object"] == obj]
    assert f"(n = {len(mine)})" in ax.get_title(loc="left")
    for column in ("accuracy", "accuracy_line"):
        assert has_line_with(ax, _bin_means(mine, column, THETA_BINS_DEG)), column


def test_tables_and_figures(tmp_path, monkeypatch):
    figures = saved_figures(monkeypatch)
    table = regrasp_table(_regrasp_rows())
    assert "70.0 % (7/10" in table and "81.8 % (9/11" in table and "93.2 %" in table
    acc_rows = [
        {"object": "obj1", "theta_deg": 1.0, "accuracy": 0.99, "accuracy_line": 0.98},
        {"object": "obj1", "theta_deg": 2.0, "accuracy": 0.97, "accuracy_line": 0.96},
        {"object": "obj1", "theta_deg": -13.0, "accuracy": 0.90, "accuracy_line": 0.80},
    ]
    acc = accuracy_table(acc_rows)
    # ours / the paper's method in our world / the paper's published obj1 at the bin centre
    # (1.25 deg: 98.7 + (97.7 - 98.7) * 1.15 / 3.1 = 98.33), grasps.
    assert "| 0–2.5 | 98.0 / 97.0 / 98.3 (2) |" in acc
    assert "| 10–12.5 | – / – / 94.4 |" in acc and "| 12.5–15 | 90.0 / 80.0 / 87.5 (1) |" in acc
    assert "| 30–45 | – |" in acc  # beyond the paper's curve: "–"
    accuracy_figure(acc_rows, tmp_path / "a.png")
    regrasp_figure(_regrasp_rows(), tmp_path / "r.png")
    accuracy, regrasp = figures
    assert [f.saved_to for f in figures] == [tmp_path / "a.png", tmp_path / "r.png"]
    # obj1: ours 98 % (0-2.5 deg: 99, 97) and 90 % (12.5-15 deg); the paper's method 97, 80
    (ax,) = axes_labelled(accuracy, "CoM accuracy (%)")
    assert ax.get_xlabel().startswith("tilt in the jaws")
    _check_accuracy_panel(accuracy, acc_rows, "obj1")
    _check_regrasp_figure(regrasp, _regrasp_rows())


def test_accuracy_table_without_the_paper_method_says_not_recorded():
    text = accuracy_table([{"object": "obj2", "theta_deg": 1.0, "accuracy": 0.99}])
    assert "not recorded" in text and "| 0–2.5 | 99.0 / n.r. / – (1) |" in text


def test_empty_bins_break_the_accuracy_curves():
    rows = [
        {"object": "obj1", "theta_deg": 1.0, "accuracy": 0.99, "accuracy_line": 0.98},
        {"object": "obj1", "theta_deg": 2.0, "accuracy": 0.97, "accuracy_line": 0.97},
        {"object": "obj1", "theta_deg": 13.0, "accuracy": 0.90, "accuracy_line": 0.80},
        {"object": "obj1", "theta_deg": 70.0, "accuracy": 0.95, "accuracy_line": 0.50},
    ]
    fig, curves = accuracy_plot._accuracy_plot(rows)
    try:
        for kind, first in (("ours", 98.0), ("line", 97.5)):
            y = np.asarray(curves["obj1"][kind].get_ydata(), float)
            # Bins (deg): 0-2.5 | 2.5-5 ... 10-12.5 | 12.5-15 | 15-20 ... 45-60 | 60-90.
            assert y[0] == pytest.approx(first)
            assert np.isnan(y[1:5]).all() and np.isfinite(y[5]) and np.isnan(y[6:11]).all()
            assert np.isfinite(y[11])
    finally:
        common.load_pyplot().close(fig)


def _acc_row(obj, theta, acc, **extra):
    length = 0.4
    row = {
        "object": obj, "theta_deg": theta, "theta_true_deg": theta, "accuracy": acc,
        "length_m": length, "pos_real_m": 0.0, "pos_esti_m": (1 - acc) * length / 5,
        "com_std_m": 1e-4, "rolled_slip": 0,
    }  # fmt: skip
    row.update(extra)
    return row


def test_error_source_names_the_dominant_error():
    from comgrasp_pin.experiments.report import error_source

    assert error_source(_acc_row("obj1", 20.0, 0.9, theta_true_deg=23.0)) == "perception (tilt)"
    # A tilt that differs by a half turn is the same line: not a perception error.
    assert error_source(_acc_row("obj1", 80.0, 0.9, theta_true_deg=-100.0)) != "perception (tilt)"
    assert error_source(_acc_row("obj1", 20.0, 0.9, rolled_slip=1)) == (
        "slip during the measurement"
    )
    # A 2-sigma torque-noise band of 2 cm covers a miss of 8 mm.
    assert error_source(_acc_row("obj1", 20.0, 0.9, com_std_m=0.01)) == "torque noise"
    assert error_source(_acc_row("obj1", 50.0, 0.9)) == "rod geometry at the tilt"


def test_accuracy_verdict_compares_every_bin_with_the_paper():
    from comgrasp_pin.experiments.report import accuracy_verdict

    rows = [_acc_row("obj1", 1.0, 0.995), _acc_row("obj1", 21.0, 0.97)]
    rows += [{"object": "obj1", "error": "RodDroppedError: dropped"}]
    text = accuracy_verdict(rows)
    # Paper obj1 at the 20-25 deg bin centre (22.5 deg): 78.7 + (73.6 - 78.7) * 1.9 / 4.9.
    paper_at = 78.7 + (73.6 - 78.7) * (22.5 - 20.6) / (25.5 - 20.6)
    assert f"{97.0 - max(paper_at, 0):+.1f} points" not in text  # the worst bin is the low one
    assert "| obj1 | 3 (1) | 99.5 % (1) | 97.0 % (1) |" in text
    assert "| yes |" in text
    assert "RodDroppedError × 1" in text
    worse = accuracy_verdict([_acc_row("obj6", 1.0, 0.90)])
    assert "| no |" in worse and "1 of 1 grasps are below 95 %" in worse


def test_regrasp_verdict_counts_reasons():
    from comgrasp_pin.experiments.report import regrasp_verdict

    rows = _regrasp_rows()
    failed = next(r for r in rows if r["method"] == "baseline" and not r["success"])
    failed["reason"] = "geometric-centre grasp; the rod ended on the table"
    text = regrasp_verdict(rows)
    assert "Regrasp overall (obj1): 9/11 (81.8 %" in text
    assert "below: obj1 82 %" in text
    assert "- regrasp: boom × 1" in text
    assert "- baseline: geometric-centre grasp, rod ended on the table × 1" in text


def test_regrasp_figure_with_every_trial_a_success(tmp_path, monkeypatch):
    figures = saved_figures(monkeypatch)
    # Wilson's upper bound for 6/6 rounds to just below 1: the error bar must not go negative.
    rows = [
        {"object": o, "trial": k, "method": m, "success": 1}
        for o in ("obj1", "obj2", "obj7")
        for k in range(6)
        for m in ("baseline", "regrasp")
    ]
    regrasp_figure(rows, tmp_path / "r.png")
    (fig,) = figures
    _check_regrasp_figure(fig, rows)  # six bars at 100 %
    (ax,) = axes_labelled(fig, "pick-and-place success (%)")
    segments = error_bar_segments(ax)  # Wilson's interval of 6/6: below 100 %, none above
    assert len(segments) == 6 and all(0 < seg[:, 1].min() < seg[:, 1].max() for seg in segments)
    assert max(seg[:, 1].max() for seg in segments) == pytest.approx(100.0)
    assert any(t.startswith("extra objects") for t in texts(fig))  # obj7 apart


# --- calibration ----------------------------------------------------------------------------


def _cal_row(obj, theta, z, std=0.004, real=0.05):
    return {
        "object": obj, "theta_deg": theta, "accuracy": 0.99, "pos_real_m": real,
        "pos_esti_m": real + z * std, "pos_std_m": std, "length_m": 0.4,
    }  # fmt: skip


def test_calibration_table_by_hand():
    # Bin 0-5 deg: z = ±0.5, ±1.5, ±2.5 -> 2/6 inside ±1σ, 4/6 inside ±1.96σ, rms
    # sqrt(8.75 / 3) = 1.71. Bin 60-90 (tilt 90 counts): z = 0.1, 0.2 -> all inside.
    zs = (0.5, -0.5, 1.5, -1.5, 2.5, -2.5)
    rows = [_cal_row("obj2", 3.0, z) for z in zs] + [
        _cal_row("obj2", -90.0, 0.1),
        _cal_row("obj2", 75.0, 0.2),
        {**_cal_row("obj2", 1.0, 0.0), "pos_std_m": ""},  # no std: left out
    ]
    text = calibration_table(rows)
    lo68, hi68 = report.wilson_interval(2, 6)
    assert f"| 0–5 | 6 | 33.3 % ({100 * lo68:.0f}–{100 * hi68:.0f}) | 66.7 % (" in text
    assert "| 1.71 | " in text and "0.00 | 95 % ≥ 90 %: not met" in text
    assert "| 60–90 | 2 | 100.0 % (" in text and "| 0.16 | +0.15 |" in text
    assert "| 5–10 | 0 | – |" in text
    # Overall: 4/8 inside ±1σ, 6/8 inside ±1.96σ, rms sqrt((8.75 * 2 + 0.01 + 0.04) / 8).
    rms = math.sqrt((17.5 + 0.05) / 8)
    assert "| **all** | 8 | 50.0 % (" in text and "| 75.0 % (" in text
    assert f"| {rms:.2f} |" in text
    assert "1 grasp(s) without a recorded std are left out" in text
    assert "95 % in 93–97 %: not met" in text


def test_calibration_well_calibrated_meets_the_targets():
    rng = np.random.default_rng(3)
    z = rng.standard_normal(4000)
    rows = [_cal_row("obj3", t, v) for t, v in zip(rng.uniform(0, 90, len(z)), z)]
    text = calibration_table(rows)
    assert "95 % in 93–97 %: met; rms z in 0.9–1.1: met" in text


def test_calibration_not_recorded(tmp_path, monkeypatch):
    figures = saved_figures(monkeypatch)
    rows = [_acc_row("obj1", 1.0, 0.99)]
    assert "not recorded" in calibration_table(rows)
    assert "not recorded" in report.calibration_section(rows, tmp_path)
    assert not (tmp_path / "calibration.png").exists()
    calibration_figure(rows, tmp_path / "c.png")
    (fig,) = figures
    assert not any(ax.get_visible() and ax.axison for ax in fig.axes)  # a note, no axes
    assert any("pos_std_m not recorded" in t and "no calibration" in t for t in texts(fig))


def _check_calibration_row(fig, rows, objects) -> None:
    """The row of ``objects``: histogram with N(0, 1) for their n; 95 % coverage and rms z
    per tilt bin and over all, computed here from z = (pos_esti - pos_real) / pos_std."""
    from comgrasp_pin.experiments.stats import CALIBRATION_BINS_DEG as edges

    mine = [r for r in rows if r["object"] in objects]
    z = np.array([(r["pos_esti_m"] - r["pos_real_m"]) / r["pos_std_m"] for r in mine])
    theta = np.abs([r["theta_deg"] for r in mine])
    k = np.searchsorted(edges, theta, side="right") - 1
    groups = [z[k == i] for i in range(len(edges) - 1) if np.any(k == i)] + [z]
    rms = [np.sqrt(np.mean(g**2)) for g in groups]
    cover95 = [100 * np.mean(np.abs(g) <= 1.96) for g in groups]
    (ax_r,) = [ax for ax in axes_labelled(fig, "rms z") if has_line_with(ax, rms, atol=1e-6)]
    ax_c = [ax for ax in fig.axes if ax.get_ylabel().startswith("grasps inside")]
    assert any(y.tolist() == pytest.approx(cover95) for ax in ax_c for _, y in error_bar_data(ax))
    (ax_h,) = [ax for ax in axes_labelled(fig, "grasps per 0.5 of z") if ax.figure is ax_r.figure]
    peak = len(z) / len(objects) * 0.5 / np.sqrt(2 * np.pi)  # N(0, 1) for n per object
    assert any(np.nanmax(line.get_ydata()) == pytest.approx(peak, rel=1e-3) for line in ax_h.lines)


def test_calibration_figure_written(tmp_path, monkeypatch):
    figures = saved_figures(monkeypatch)
    rng = np.random.default_rng(0)
    rows = [_cal_row("obj1", t, z) for t, z in zip(rng.uniform(0, 80, 60), rng.normal(size=60))]
    rows += [
        _cal_row("obj7", t, 3 * z) for t, z in zip(rng.uniform(0, 80, 20), rng.normal(size=20))
    ]
    calibration_figure(rows, tmp_path / "c.png")
    (fig,) = figures
    assert len(axes_labelled(fig, "rms z")) == 2  # the paper's objects, the extra one
    _check_calibration_row(fig, rows, ["obj1"])
    _check_calibration_row(fig, rows, ["obj7"])  # z three times too large: rms about 3
    assert "![calibration](calibration.png)" in report.calibration_section(rows, tmp_path)
    assert figures[1].saved_to == tmp_path / "calibration.png"
    _check_calibration_row(figures[1], rows, ["obj1"])


# --- ours against the paper's method ----------------------------------------------------------


def test_method_comparison_by_hand():
    # 20-30 deg: ours 99, 98, 97 % against the paper's method 96 % each: differences 3, 2, 1
    # points, mean 2, s = 1, se = 1 / sqrt(3), t(0.975, 2) = 4.302653 -> 2 ± 2.484.
    rows = [
        _acc_row("obj1", 25.0, a, accuracy_line=0.96, pos_esti_line_m=0.0)
        for a in (0.99, 0.98, 0.97)
    ]
    rows.append(_acc_row("obj1", 1.0, 0.99, accuracy_line=0.99, pos_esti_line_m=0.0))
    text = method_comparison(rows)
    assert "| 20–30 | 3 | 98.0 | 96.0 | +2.00 (-0.48 to +4.48) | 3 | 0 | 0 |" in text
    assert "| 0–10 | 1 | 99.0 | 99.0 | +0.00 (n < 2) | 0 | 0 | 1 |" in text
    assert "| 10–20 | 0 |" in text
    assert "no clear difference at 0–10°, 20–30°" in text


def test_method_comparison_explains_with_the_offset_of_the_com(monkeypatch):
    # The paper's one-pose line misses by h·tan θ with h = 13 mm; ours by 1 mm·tan θ.
    monkeypatch.setattr(accuracy_tables, "com_off_axis_m", lambda obj: 0.013)
    rows = []
    for theta in (15.0, 25.0, 40.0, 60.0):
        t = math.tan(math.radians(theta))
        rows.append(
            _acc_row("obj1", theta, 1 - 5 * 0.001 * t / 0.4, pos_esti_m=0.001 * t,
                     pos_esti_line_m=0.013 * t, accuracy_line=1 - 5 * 0.013 * t / 0.4)
        )  # fmt: skip
    text = method_comparison(rows)
    assert "| obj1 | 13.0 | 4 | 13.0 | 1.0 |" in text
    assert "close to the model's h for obj1" in text


def test_method_comparison_without_the_column():
    assert "not recorded" in method_comparison([_acc_row("obj1", 1.0, 0.99)])


# --- extra objects stay apart ------------------------------------------------------------------


def test_object_groups_without_paper_objects_from_the_simulation(monkeypatch):
    monkeypatch.setattr(common, "paper_objects", lambda: report.DEFAULT_PAPER_OBJECTS)
    rows = [{"object": o} for o in ("obj7", "obj10", "obj1", "obj9", "obj6")]
    assert report.object_groups(rows) == (["obj1", "obj6"], ["obj7", "obj9", "obj10"])


def test_extra_objects_never_enter_the_paper_comparison(tmp_path, monkeypatch):
    figures = saved_figures(monkeypatch)
    paper_rows = [
        _acc_row("obj1", th, a, accuracy_line=al, pos_esti_line_m=0.01, pos_std_m=0.002)
        for th, a, al in ((1.0, 0.995, 0.99), (12.0, 0.98, 0.95), (27.0, 0.97, 0.90))
    ]
    # obj7: far worse, in the same bins. Were it pooled, every number would move.
    extra_rows = [
        _acc_row("obj7", th, 0.5, accuracy_line=0.1, pos_esti_line_m=0.2, pos_std_m=1e-5)
        for th in (1.0, 12.0, 27.0)
    ]
    both = paper_rows + extra_rows
    for fn in (method_comparison, report.accuracy_verdict, calibration_table):
        assert fn(both) == fn(paper_rows), fn.__name__
        assert "obj7" not in fn(both)
    table = accuracy_table(both)
    paper_part, extra_part = table.split("Extra objects (not in the paper), apart:")
    assert paper_part.strip() == accuracy_table(paper_rows).strip() and "obj7" in extra_part
    reg = [
        {"object": o, "trial": k, "method": m, "success": int(o == "obj1")}
        for o in ("obj1", "obj7")
        for k in range(4)
        for m in ("baseline", "regrasp")
    ]
    reg_paper = [r for r in reg if r["object"] == "obj1"]
    assert report.regrasp_verdict(reg) == report.regrasp_verdict(reg_paper)
    table = regrasp_table(reg)
    assert table.index("extra objects, not in the paper") < table.index("| obj7 |")
    # The extra objects' own section has them, each on its own.
    section = report.extra_objects_section(both, reg)
    assert "### obj7" in section and "Objects obj7;" in section and "obj1" not in section
    assert report.extra_objects_section(paper_rows, reg_paper) == "No extra objects in this run."
    # The accuracy figure gives obj7 a panel of its own, away from the paper's.
    fig, curves = accuracy_plot._accuracy_plot(both)
    try:
        obj1_ax, obj7_ax = curves["obj1"]["ours"].axes, curves["obj7"]["ours"].axes
        assert obj1_ax is not obj7_ax
        assert obj1_ax.figure is not obj7_ax.figure  # another subfigure
        assert (
            curves["obj7"]["line"] in obj7_ax.lines and curves["obj7"]["ours"] not in obj1_ax.lines
        )
    finally:
        common.load_pyplot().close(fig)
    accuracy_figure(both, tmp_path / "a.png")
    calibration_figure(both, tmp_path / "c.png")
    accuracy, calibration = figures
    _check_accuracy_panel(accuracy, both, "obj1")  # obj1's means: obj7 not pooled in
    _check_accuracy_panel(accuracy, both, "obj7")
    _check_calibration_row(calibration, both, ["obj1"])
    _check_calibration_row(calibration, both, ["obj7"])


# --- the extra measurement pose ------------------------------------------------------------------


def test_extra_pose_summary_counts_what_it_bought():
    rows = []
    for k, (extra, ok, base_ok) in enumerate(((1, 1, 0), (1, 1, 0), (1, 0, 1), (0, 1, 1))):
        rows.append({"object": "obj3", "trial": k, "seed": 3000 + k, "method": "regrasp",
                     "success": ok, "extra_pose": extra})  # fmt: skip
        rows.append({"object": "obj3", "trial": k, "seed": 3000 + k, "method": "baseline",
                     "success": base_ok})  # fmt: skip
    text = extra_pose_summary(rows)
    assert "| obj3 | 4 | 3 of 4 | 2/3 (67 %," in text and "| 1/1 (100 %," in text
    assert "| 1/3 (33 %) |" in text  # the baseline on the three scenes with the extra pose
    assert "one more pose in 3 of 4 regrasp trials" in text
    no_column = [{k: v for k, v in r.items() if k != "extra_pose"} for r in rows]
    assert "not recorded" in extra_pose_summary(no_column)


# --- the run summary and reproduce()'s report with runs from two seeds ----------------------------


def test_run_summary_counts_the_rows_of_two_seeds():
    acc = [{"object": o, "seed": s * 100_000 + 1000 + k, "method": "trial"}
           for s in (0, 1) for o in ("obj1", "obj7") for k in range(3)]  # fmt: skip
    reg = [{"object": "obj1", "seed": s * 100_000 + 1000 + k, "method": m, "success": 1}
           for s in (0, 1) for k in range(3) for m in ("baseline", "regrasp")]  # fmt: skip
    text = report.run_summary(acc, reg, seed=0)
    assert "12 accuracy grasps and 12 pick-and-place trials" in text
    assert "6 per object and method" in text and "seeds 0, 1 pooled" in text
    assert "extra objects obj7, reported apart" in text


@pytest.mark.parametrize("new_columns", [False, True])
def test_reproduce_report_with_two_seeds_and_an_extra_object(tmp_path, monkeypatch, new_columns):
    from comgrasp_pin.experiments import reproduce as rep

    rng = np.random.default_rng(1)
    acc, reg = [], []
    for seed in (0, 1):
        for obj in ("obj1", "obj6", "obj7"):
            for k in range(4):
                trial_seed = seed * 100_000 + int(obj[3:]) * 1000 + k
                theta = float(rng.uniform(0, 70))
                row = _acc_row(obj, theta, 0.99, accuracy_line=0.97, pos_esti_line_m=0.01,
                               seed=trial_seed, trial=k, method="trial")  # fmt: skip
                if new_columns:
                    row.update(pos_std_m=0.003, estimator="ipopt", accuracy_wrench=0.995,
                               accuracy_both=0.996, pos_esti_wrench_m=row["pos_real_m"],
                               pos_std_wrench_m=0.002, wrench_share_com=0.8)  # fmt: skip
                acc.append(row)
                for method in ("baseline", "regrasp"):
                    r = {"object": obj, "trial": k, "seed": trial_seed, "method": method,
                         "success": int(method == "regrasp" or k % 2), "error": ""}  # fmt: skip
                    if new_columns and method == "regrasp":
                        r["extra_pose"] = k % 2
                    reg.append(r)
    monkeypatch.setattr(rep, "run_accuracy", lambda opts, draw: acc)
    monkeypatch.setattr(rep, "run_regrasp", lambda opts, draw: reg)
    text = rep.reproduce(rep.RunOptions(out=tmp_path, trials=4)).read_text()
    assert "seeds 0, 1 pooled" in text and "8 per object and method" in text
    for heading in ("## Calibration", "### Ours against the paper's method",
                    "### The extra measurement pose", "## Extra objects", "### obj7"):  # fmt: skip
        assert heading in text
    assert ("![calibration](calibration.png)" in text) == new_columns
    assert ("not recorded" in text.split("## Experiment 2")[0]) != new_columns
    wrist = text.split("### The wrist force/torque sensor")[1].split("\n## ")[0]
    assert ("| obj1 | " in wrist) == new_columns
    assert (tmp_path / "calibration.png").exists() == new_columns


def test_reproduce_with_a_second_seed_runs_accuracy_again_and_reports_it(tmp_path, monkeypatch):
    from comgrasp_pin.experiments import reproduce as rep

    calls = []

    def fake_accuracy(opts, draw):
        calls.append(opts)
        # the second seed's grasps: every estimate 1 mm off with a 1 mm std (z = 1)
        return [_acc_row("obj1", 10.0 * k, 0.99, seed=opts.seed * 100_000 + 1000 + k, trial=k,
                         method="trial", pos_std_m=0.001, pos_esti_m=0.011, pos_real_m=0.01,
                         estimator="ipopt") for k in range(4)]  # fmt: skip

    monkeypatch.setattr(rep, "run_accuracy", fake_accuracy)
    monkeypatch.setattr(rep, "run_regrasp", lambda opts, draw: [])
    opts = rep.RunOptions(out=tmp_path, trials=4, second_seed=7, sensors="realistic")
    text = rep.reproduce(opts).read_text()
    # the headline, the second seed with its sensors and with ideal ones, the ideal headline
    assert [(c.seed, c.sensors) for c in calls] == [(0, "realistic"), (7, "realistic"),
                                                    (7, "ideal"), (0, "ideal")]  # fmt: skip
    assert calls[1].out == tmp_path / "seed7" and calls[1].second_seed is None
    assert calls[2].out == tmp_path / "ideal" / "seed7" and calls[2].second_seed is None
    section = text.split("## A second seed: the accuracy experiment with seed 7")[1]
    section = section.split("## Experiment 2")[0]
    for preset, folder in (("realistic", "seed7/"), ("ideal", "ideal/seed7/")):
        assert f"### `{preset}` sensors (files in `{folder}`)" in section
    assert section.count("| tilt bin (deg) | n | coverage ±1σ (68 %)") == 2
    assert "rms z" in section


def test_reproduce_draws_each_parts_files_beside_the_next_part_and_raises_their_errors(
    tmp_path, monkeypatch
):
    """A part's figures are drawn in a thread while the next part runs: every drawing has
    ended when reproduce returns (its files there), and one that fails fails the run."""
    import threading
    import time

    from comgrasp_pin.experiments import reproduce as rep

    rows = [_acc_row("obj1", 10.0 * k, 0.99, seed=1000 + k, trial=k, method="trial")
            for k in range(4)]  # fmt: skip
    drawn_in = []

    def slow_drawing(path):
        def job():
            time.sleep(0.2)  # still drawing when the next part starts
            drawn_in.append(threading.current_thread().name)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text("drawn")

        return job

    def fake_accuracy(opts, draw):
        draw(slow_drawing(opts.out / f"accuracy_{opts.sensors}.txt"))
        return rows

    def fake_regrasp(opts, draw):
        draw(slow_drawing(opts.out / f"regrasp_{opts.sensors}.txt"))
        return []

    monkeypatch.setattr(rep, "run_accuracy", fake_accuracy)
    monkeypatch.setattr(rep, "run_regrasp", fake_regrasp)
    rep.reproduce(rep.RunOptions(out=tmp_path, trials=4, sensors="realistic"))
    for name in ("accuracy_realistic", "regrasp_realistic"):
        assert (tmp_path / f"{name}.txt").read_text() == "drawn"
    assert (tmp_path / "ideal" / "accuracy_ideal.txt").read_text() == "drawn"
    assert len(drawn_in) == 4 and all(n.startswith("report") for n in drawn_in)

    def broken(opts, draw):
        draw(lambda: 1 / 0)
        return rows

    monkeypatch.setattr(rep, "run_accuracy", broken)
    with pytest.raises(ZeroDivisionError):
        rep.reproduce(rep.RunOptions(out=tmp_path / "broken", trials=4))


def test_the_trials_own_time_sums_every_rows_wall_time(tmp_path):
    """run.json's trial_core_minutes: every row of the run's CSVs (the headline's, ideal/,
    seed<S>/, ideal/seed<S>/), error rows without a wall time counting 0; other folders'
    CSVs not."""
    from comgrasp_pin.experiments.reproduce import RunOptions, _run_folders, _trial_minutes

    files = {"accuracy.csv": ["30", "90"], "ideal/regrasp.csv": ["60", ""],
             "seed1/accuracy.csv": ["120"], "ideal/seed1/accuracy.csv": ["6"],
             "other.csv": ["6000"],
             "sensitivity/ideal/accuracy.csv": ["6000"]}  # fmt: skip
    for name, walls in files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("object,wall_s\n" + "".join(f"obj1,{w}\n" for w in walls))
    folders = _run_folders(RunOptions(out=tmp_path, second_seed=1))
    assert _trial_minutes(folders) == pytest.approx((30 + 90 + 60 + 120 + 6) / 60)


def test_the_run_time_names_the_parts_that_ran():
    from comgrasp_pin.experiments.reproduce import _parts

    meta = {"accuracy_minutes": 0.7, "regrasp_minutes": 1.4, "second_seed_minutes": 0.0,
            "ideal_minutes": 1.38}  # fmt: skip
    assert _parts(meta) == "accuracy 0.7, pick-and-place 1.4, ideal sensors 1.4 min"
    meta.update(second_seed_minutes=16.0, ideal_minutes=0.0)
    assert _parts(meta) == "accuracy 0.7, pick-and-place 1.4, the second seed 16.0 min"
