"""The realistic-against-ideal section of the report, on rows whose measures are known."""

import pytest
from _figures import axes_labelled, bars, saved_figures

from comgrasp_pin.experiments.report.sensors import sensors_comparison


def _acc(obj, theta, accuracy, line, z, error=""):
    return {"object": obj, "theta_deg": theta, "accuracy": accuracy, "accuracy_line": line,
            "pos_esti_m": 0.001 * z, "pos_real_m": 0.0, "pos_std_m": 0.001,
            "error": error}  # fmt: skip


def _reg(obj, method, success, error=""):
    return {"object": obj, "method": method, "success": success, "error": error}


def test_side_by_side_measures_by_hand():
    acc = [
        _acc("obj1", 10.0, 0.98, 0.96, 0.5),
        _acc("obj2", -20.0, 0.96, 0.90, 3.0),
        _acc("obj2", 50.0, 0.50, 0.10, 0.1),
        _acc("obj7", 10.0, 0.0, 0.0, 9.0),
        {**_acc("obj3", 0, "", "", 0), "error": "comgrasp_pin.errors.UntrustedImageError: x"},
    ]
    reg = [_reg("obj1", "regrasp", 1), _reg("obj1", "baseline", 0),
           _reg("obj2", "regrasp", 0, "comgrasp_pin.errors.AmbiguousObjectError: y"),
           _reg("obj2", "baseline", 1)]  # fmt: skip
    ideal_acc = [_acc("obj1", 5.0, 0.99, 0.99, 1.0)]
    ideal_reg = [_reg("obj1", "regrasp", 1), _reg("obj1", "baseline", 1)]
    text = sensors_comparison(acc, reg, ideal_acc, ideal_reg, "realistic")
    rows = {line.split(" | ")[0].strip("| "): line.split(" | ")[1:] for line in text.splitlines()}
    # below 30 deg (|theta|): 98 and 96 -> 97.0; the paper's method 96 and 90 -> 93.0; obj7 is
    # an extra object, the 50 deg grasp beyond the range
    assert rows["mean accuracy below 30°, ours (%)"][0].startswith("97.0 ")
    assert rows["mean accuracy below 30°, the paper's method (%)"][0].startswith("93.0 ")
    assert rows["mean accuracy below 30°, ours (%)"][1].startswith("99.0 (n 1)")
    assert rows["worst grasp below 30°, ours (%)"][0] == "96.0"
    # z = 0.5, 3.0, 0.1: two of three within 1.96
    assert rows["95 % interval covers the truth (%)"][0].startswith("66.7 ")
    assert rows["accuracy grasps refused or failed"][0] == "1 of 4"
    assert "(1/2)" in rows["pick-and-place, regrasp planner (%)"][0]
    assert "(1/2)" in rows["pick-and-place, geometric-centre baseline (%)"][0]
    assert rows["UntrustedImageError"] == ["1", "0 |"]  # (the last cell keeps its bar)
    assert rows["AmbiguousObjectError"][0] == "1"


def test_the_sources_table_and_figure(tmp_path, monkeypatch):
    """One row per preset, the same measures as the comparison; a figure a person reads."""
    from comgrasp_pin.experiments.report.sensors import sources_figure, sources_table

    runs = {"ideal": [_acc("obj1", 10.0, 0.99, 0.98, 0.5), _acc("obj2", 5.0, 0.97, 0.95, 1.0)],
            "ideal+torque_drift": [_acc("obj1", 10.0, 0.95, 0.94, 0.2),
                                   {**_acc("obj2", 0, "", "", 0), "error": "X: y"}]}  # fmt: skip
    lines = sources_table(runs).splitlines()
    assert lines[0].startswith("| sensors | mean accuracy below 30°, ours (%)")
    assert lines[2].startswith("| ideal | 98.0 ") and lines[2].endswith("| 0 of 2 |")
    assert lines[3].startswith("| ideal+torque_drift | 95.0 (n 1) ") and "1 of 2" in lines[3]
    path = tmp_path / "sources.png"
    figures = saved_figures(monkeypatch)
    sources_figure(runs, path)
    (fig,) = figures
    assert fig.saved_to == path and path.is_file()
    (ax,) = axes_labelled(fig, "mean accuracy, tilt below 30°")
    assert [t.get_text() for t in ax.get_xticklabels()] == ["ideal", "+torque_drift"]
    # per preset, ours then the paper's method: ideal (99 + 97) / 2 and (98 + 95) / 2; with
    # the torque drift obj2 failed: obj1's 95 and 94
    assert [h for _, h in bars(ax)] == pytest.approx([98.0, 96.5, 95.0, 94.0])
    assert [t.get_text() for t in ax.texts] == ["0/2\nrefused", "1/2\nrefused"]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["ours", "the paper's method"]


def test_the_wrist_sensor_table_compares_grasp_by_grasp_below_30_deg():
    from comgrasp_pin.experiments.report import wrist_sensor_table

    rows = []
    for k in range(6):
        for obj, joints, wrench in (("obj1", 0.95, 0.99), ("obj2", 0.99, 0.90)):
            rows.append({
                "object": obj, "trial": k, "theta_deg": 5.0 + k, "accuracy": joints,
                "accuracy_wrench": wrench + 0.001 * k, "accuracy_both": 0.98,
                "pos_real_m": 0.0, "pos_esti_wrench_m": 0.001 * (k - 2.5),
                "pos_std_wrench_m": 0.002, "wrench_share_com": 0.75, "pos_esti_m": 0.0,
            })  # fmt: skip
        rows.append({"object": "obj1", "trial": 9, "theta_deg": 60.0, "accuracy": 0.5,
                     "accuracy_wrench": 0.1, "pos_real_m": 0.0, "pos_esti_m": 0.0})  # fmt: skip
    text = wrist_sensor_table(rows, objects=["obj1", "obj2"])
    obj1 = next(line for line in text.splitlines() if line.startswith("| obj1 |"))
    cells = [c.strip() for c in obj1.strip("|").split("|")]
    assert cells[1] == "6"  # the 60 deg grasp is left out
    assert cells[2] == "95.0" and abs(float(cells[3]) - 99.25) < 0.06 and cells[8] == "75"
    assert cells[5].startswith("+4.25") and cells[9] == "as accurate or more"
    assert "less accurate for obj2" in text and "for 1 of 2 objects" in text
