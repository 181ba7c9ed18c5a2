"""`comgrasp sweep` (issue 16): config values by dotted path, the grid, its validation, and a
real tiny sweep whose default point gives the accuracy experiment's own row."""

import itertools
import json

import numpy as np
import pytest
from _figures import axes_labelled, error_bar_data, error_bar_segments, saved_figures

from comgrasp_pin.cli import main
from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.config import paths as config_paths
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.experiments.reproduce import RunOptions
from comgrasp_pin.experiments.runner import read_rows
from comgrasp_pin.experiments.sweep import (
    MEASURES,
    SweepOptions,
    grid,
    markdown_table,
    parse_param,
    point_measures,
    summarise,
    sweep_tasks,
)


def test_values_by_dotted_path_alias_and_tuple_element():
    config = config_paths.with_values(
        EpisodeConfig(),
        {"grip_force": 10, "sensors.torque.noise_std": 0.2, "world.pad_friction": 0.5,
         "world.pad_friction.1": 0.004, "world.noslip_iterations": 20},
    )  # fmt: skip
    assert config.motion.grip_force == 10.0
    assert config.sensors.torque.noise_std == 0.2
    assert config.world.pad_friction == (0.5, 0.004, 0.0001)
    assert config.world.noslip_iterations == 20 and isinstance(config.world.noslip_iterations, int)
    assert EpisodeConfig().motion.grip_force == 15.0  # the default is untouched
    assert config_paths.resolve("noise") == "sensors.torque.noise_std"
    assert config_paths.resolve("world.pad_friction") == "world.pad_friction.0"


@pytest.mark.parametrize(
    ("text", "message"),
    [("grip=1,2", "unknown config value 'grip'"),
     ("motion.grip_forces=1", "unknown config value 'motion.grip_forces'"),
     ("trial.estimator=1", "unknown config value 'trial.estimator'"),
     ("grip_force=", "needs a comma-separated list of numbers"),
     ("grip_force=10,,20", "needs a comma-separated list of numbers"),
     ("grip_force=ten", "values must be numbers"),
     ("grip_force=10,nan", "values must be finite"),
     ("grip_force=10,10", "listed more than once"),
     ("grip_force", "needs NAME=V1,V2")],
)  # fmt: skip
def test_bad_params_are_refused(text, message):
    with pytest.raises(InvalidInputError, match=message):
        parse_param(text)


def test_an_unknown_path_lists_the_valid_ones():
    with pytest.raises(InvalidInputError) as info:
        parse_param("motion.grip=1")
    text = str(info.value)
    assert "motion.grip_force" in text and "sensors.torque.noise_std" in text
    assert "grip_force (motion.grip_force)" in text


@pytest.mark.parametrize(
    ("param", "message"),
    [("motion.grip=1", "motion.grip_force"),  # the valid paths are listed
     ("noise=", "needs a comma-separated list"),
     ("noise=-0.1,0.1", "coulomb and viscous must be >= 0"),
     ("world.noslip_iterations=2.5", "world.noslip_iterations takes an integer")],
)  # fmt: skip
def test_the_cli_refuses_bad_params_with_exit_2(tmp_path, capsys, param, message):
    out = tmp_path / "sweep"
    try:
        code = main(["sweep", "--param", param, "--objects", "obj1", "--trials", "1",
                     "--out", str(out)])  # fmt: skip
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err
    assert not out.exists()


def test_the_grid_and_its_tasks_share_the_seeds(tmp_path):
    params = (("motion.grip_force", (10.0, 20.0)), ("sensors.torque.noise_std", (0.02, 0.05, 0.1)))
    points = grid(params)
    assert len(points) == 6 and points[1] == {"motion.grip_force": 10.0,
                                              "sensors.torque.noise_std": 0.05}  # fmt: skip
    opts = SweepOptions(RunOptions(tmp_path, ("obj1", "obj2"), 2), "regrasp", params)
    tasks = sweep_tasks(opts)
    assert len(tasks) == 6 * 2 * 2 * 2  # points x objects x trials x methods
    seeds = {}
    for task in tasks:
        seeds.setdefault((task["object"], task["trial"]), set()).add(task["seed"])
        assert task["overrides"]["motion.grip_force"] == task["motion.grip_force"]
    assert all(len(s) == 1 for s in seeds.values())


def _row(accuracy, esti, real, std, **extra):
    return {"accuracy": accuracy, "pos_esti_m": esti, "pos_real_m": real, "pos_std_m": std,
            "error": "", **extra}  # fmt: skip


def test_point_measures_by_hand():
    rows = [_row(0.9, 0.01, 0.0, 0.01), _row(0.7, 0.03, 0.0, 0.01),
            {**_row("", "", "", ""), "error": "RodDroppedError: dropped"}]  # fmt: skip
    m = point_measures(rows, "accuracy")
    assert m["accuracy"][0] == pytest.approx(80.0) and m["accuracy"][3] == 2
    # t interval of (90, 70): 80 +- t_{0.975,1} * 14.142 / sqrt(2) = 80 +- 127.06
    assert m["accuracy"][2] - 80.0 == pytest.approx(12.706 * 10.0, rel=1e-3)
    assert m["success"][:1] == (pytest.approx(200 / 3),) and m["success"][3] == 3
    assert m["coverage"][0] == pytest.approx(50.0) and m["coverage"][3] == 2  # z = 1 and 3
    regrasp = [{**_row(0.9, 0.0, 0.0, 0.01), "method": "regrasp", "success": 1},
               {**_row(0.8, 0.0, 0.0, 0.01), "method": "regrasp", "success": 0},
               {**_row(0.1, 0.0, 0.0, 0.01), "method": "baseline", "success": 1}]  # fmt: skip
    m = point_measures(regrasp, "regrasp")
    assert m["success"][0] == pytest.approx(50.0) and m["accuracy"][0] == pytest.approx(85.0)


@pytest.mark.slow
def test_a_tiny_sweep_gives_the_experiments_row_at_the_default_point(tmp_path, monkeypatch):
    acc = tmp_path / "acc"
    assert main(["accuracy", "--objects", "obj1", "--trials", "1", "--workers", "1",
                 "--out", str(acc)]) == 0  # fmt: skip
    out = tmp_path / "sweep"
    argv = ["sweep", "--param", "grip_force=15,25", "--param", "noise=0.05,0.5", "--objects",
            "obj1", "--trials", "1", "--workers", "2", "--out", str(out)]  # fmt: skip
    figures = saved_figures(monkeypatch)
    assert main(argv) == 0
    rows = read_rows(out / "sweep.csv")
    assert len(rows) == 4 and all(r["error"] == "" for r in rows)
    assert list(rows[0])[:2] == ["motion.grip_force", "sensors.torque.noise_std"]
    by_point = {(float(r["motion.grip_force"]), float(r["sensors.torque.noise_std"])): r
                for r in rows}  # fmt: skip
    reference = read_rows(acc / "accuracy.csv")[0]
    default = by_point[(15.0, 0.05)]
    assert {k: v for k, v in reference.items() if k != "wall_s"} == {
        k: default[k] for k in reference if k != "wall_s"
    }
    # ten times the torque noise moves the estimate; a firmer grip holds the rod otherwise
    assert by_point[(15.0, 0.5)]["mass_esti_kg"] != default["mass_esti_kg"]
    assert by_point[(25.0, 0.05)]["theta_true_deg"] != default["theta_true_deg"]
    # a heatmap per measure: grip force down, noise across, each cell the point's value
    # computed here from its one trial (accuracy and coverage of the 95 % interval in %)
    assert [f.saved_to for f in figures] == [out / f"sweep_{m}.png" for m in MEASURES]
    for fig, measure in zip(figures, MEASURES):
        (ax,) = axes_labelled(fig, "motion.grip_force")
        assert ax.get_xlabel() == "sensors.torque.noise_std" and ax.get_title() == MEASURES[measure]
        expected = np.empty((2, 2))
        for (i, grip), (j, noise) in itertools.product(enumerate((15.0, 25.0)),
                                                       enumerate((0.05, 0.5))):  # fmt: skip
            r = by_point[(grip, noise)]
            miss = abs(float(r["pos_esti_m"]) - float(r["pos_real_m"]))
            covered = miss <= 1.96 * float(r["pos_std_m"])
            values = {"accuracy": float(r["accuracy"]), "success": 1.0, "coverage": covered}
            expected[i, j] = 100 * values[measure]
        np.testing.assert_allclose(ax.images[0].get_array(), expected, rtol=1e-9)
    table = (out / "sweep_table.md").read_text()
    assert table.count("\n") == 2 + 4 and "| 25 | 0.5 |" in table
    settings = json.loads((out / "sweep.settings.json").read_text())
    assert settings["params"] == {"motion.grip_force": [15.0, 25.0],
                                  "sensors.torque.noise_std": [0.05, 0.5]}  # fmt: skip
    assert settings["points"][3]["config"]["motion"]["grip_force"] == 25.0
    assert settings["points"][3]["config"]["sensors"]["torque"]["noise_std"] == 0.5
    # resumable: nothing left to run; another grid is refused, naming what differs
    before = (out / "sweep.csv").read_bytes()
    assert main([*argv, "--resume"]) == 0
    assert (out / "sweep.csv").read_bytes() == before
    other = [a.replace("grip_force=15,25", "grip_force=15,30") for a in argv]
    assert main([*other, "--resume"]) == 2
    # one swept value: a line plot with intervals
    one = (("motion.grip_force", (15.0, 25.0)),)
    sel = [r for r in rows if float(r["sensors.torque.noise_std"]) == 0.05]
    table = summarise(sel, one, "accuracy")
    assert [point for point, _ in table] == [{"motion.grip_force": 15.0},
                                             {"motion.grip_force": 25.0}]  # fmt: skip
    assert np.isfinite(table[0][1]["accuracy"][0]) and "| 15 |" in markdown_table(table, one)
    from comgrasp_pin.experiments.report.sweep_plot import sweep_figures

    assert len(sweep_figures(table, one, tmp_path, MEASURES)) == 3


def test_a_line_figure_of_points_at_0_and_100_percent(tmp_path, monkeypatch):
    """Every trial a success, no interval covering the truth: a Wilson interval then ends
    at 0 % plus (or 100 % less) a rounding error, which must not make a negative error bar
    (matplotlib refuses those)."""
    from comgrasp_pin.experiments.report.sweep_plot import sweep_figures

    params = [parse_param("trial.approach_deg=0,3")]
    rows = [{**_row(0.99, 0.05, 0.0, 0.01), "trial.approach_deg": v} for v in (0.0, 3.0) * 11]
    table = summarise(rows, params, "accuracy")
    assert all(m["success"][0] == 100.0 and m["coverage"][0] == 0.0 for _, m in table)
    figures = saved_figures(monkeypatch)
    written = sweep_figures(table, params, tmp_path, MEASURES)
    assert [p.name for p in written] == [f"sweep_{m}.png" for m in MEASURES]
    assert [f.saved_to for f in figures] == written
    # each trial: accuracy 99 %, a success, its interval (0.05 +- 1.96 * 0.01) missing 0
    for fig, (measure, label), y in zip(figures, MEASURES.items(), (99.0, 100.0, 0.0)):
        (ax,) = axes_labelled(fig, label)
        assert ax.get_xlabel() == "trial.approach_deg"
        ((x, drawn),) = error_bar_data(ax)
        np.testing.assert_allclose(x, [0.0, 3.0])
        np.testing.assert_allclose(drawn, [y, y], atol=1e-9)
        assert all(seg[:, 1].min() >= 0 for seg in error_bar_segments(ax)), measure


def test_a_pick_and_place_part_hands_out_each_scenes_long_trial_first_and_ends_on_a_short_one():
    from comgrasp_pin.experiments.trials import REGRASP_TASK_METHODS, make_tasks

    objects = ["obj1", "obj2", "obj3"]
    tasks = make_tasks(objects, 3, 0, REGRASP_TASK_METHODS)
    order = {(t["object"], t["trial"], t["method"]): i for i, t in enumerate(tasks)}
    for obj in objects:
        for k in range(3):
            assert order[(obj, k, "regrasp")] < order[(obj, k, "baseline")]
    assert tasks[-1]["method"] == "baseline"  # the other worker does not wait on a long one
    assert {t["object"] for t in tasks[: 2 * len(objects)]} == set(objects)  # all early
    assert len(order) == len(tasks) == 18
