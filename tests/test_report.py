"""Report tables and figures from known rows."""

from comgrasp_pin.experiments.report import (
    accuracy_figure,
    accuracy_table,
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


def test_success_rates_count_errors_as_failures():
    rates = success_rates(_regrasp_rows())
    assert rates[("obj1", "baseline")] == (7, 10)
    assert rates[("obj1", "regrasp")] == (9, 11)


def test_tables_and_figures(tmp_path):
    table = regrasp_table(_regrasp_rows())
    assert "70.0 % (7/10" in table and "81.8 % (9/11" in table and "93.2 %" in table
    acc_rows = [
        {"object": "obj1", "theta_deg": 1.0, "accuracy": 0.99},
        {"object": "obj1", "theta_deg": 2.0, "accuracy": 0.97},
        {"object": "obj1", "theta_deg": -13.0, "accuracy": 0.90},
    ]
    acc = accuracy_table(acc_rows)
    assert "| 0–2.5 | 98.0 (2) |" in acc
    assert "| 10–12.5 | –" in acc and "| 12.5–15 | 90.0 (1) |" in acc
    for fig in (
        accuracy_figure(acc_rows, tmp_path / "a.png"),
        regrasp_figure(_regrasp_rows(), tmp_path / "r.png"),
    ):
        assert fig.stat().st_size > 10_000


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
    assert "Regrasp overall: 9/11 (81.8 %" in text
    assert "below: obj1 82 %" in text
    assert "- regrasp: boom × 1" in text
    assert "- baseline: geometric-centre grasp, rod ended on the table × 1" in text


def test_regrasp_figure_with_every_trial_a_success(tmp_path):
    # Wilson's upper bound for 6/6 rounds to just below 1: the error bar must not go negative.
    rows = [
        {"object": o, "trial": k, "method": m, "success": 1}
        for o in ("obj1", "obj2")
        for k in range(6)
        for m in ("baseline", "regrasp")
    ]
    assert regrasp_figure(rows, tmp_path / "r.png").stat().st_size > 10_000
