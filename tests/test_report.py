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
