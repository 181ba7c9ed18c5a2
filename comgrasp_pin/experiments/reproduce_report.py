"""The markdown of ``comgrasp reproduce``'s report: its sections and its words.

``report_markdown`` lays the runs' tables, figures and verdicts (``experiments.report``) into
``report.md`` with the settings and the run's time; running the experiments is
``experiments.reproduce``'s.
"""

from __future__ import annotations

from dataclasses import dataclass

from comgrasp_pin.experiments import report


@dataclass(frozen=True)
class ReportSections:
    """What the runs gave the report: the accuracy and pick-and-place rows, and the
    sections written already (calibration, the second seed's, the ideal sensors'; "" where
    that part did not run)."""

    accuracy: list
    regrasp: list
    calibration: str
    second_seed: str
    ideal: str


def report_markdown(
    meta: dict, sensors: str, noise: float, parts: str, sections: ReportSections
) -> str:
    """``report.md``'s text: ``meta`` as ``run.json`` records it, ``sensors`` the sensor
    preset, ``noise`` the torque noise (N m per sample), ``parts`` the minutes of each part
    of the run in words."""
    acc, reg, trial = sections.accuracy, sections.regrasp, meta["settings"]["trial"]
    return (
        _run_part(meta, sensors, parts, acc, reg)
        + _accuracy_part(trial, acc)
        + f"{sections.calibration}\n\n{sections.second_seed}\n{sections.ideal}\n"
        + _regrasp_part(acc, reg)
        + _settings_part(noise, meta["settings"], meta["versions"])
    )


def _run_part(meta: dict, sensors: str, parts: str, acc: list, reg: list) -> str:
    """The title, what ran and how long it took."""
    beside = "" if sensors == "ideal" else " (ideal sensors beside it below)"
    workers, backend = meta["workers"], meta["backend"]
    return f"""# comgrasp_pin: the paper's experiments, reproduced

{report.run_summary(acc, reg, meta["seed"])}
Sensors: the `{sensors}` preset{beside}.
Run time on {workers or "all the cluster's"} worker(s) ({backend} backend):
{meta["total_minutes"]:.1f} min in all ({parts}); a resumed run counts its last part
only. The trials' own time, every row's `wall_s` together: {meta["trial_core_minutes"]:.1f}
core-minutes.

"""


def _accuracy_part(trial: dict, acc: list) -> str:
    """Experiment 1 (CoM accuracy) and the calibration section's head; ``trial``: the
    trial grasp's settings."""
    return f"""## Experiment 1: CoM accuracy against the tilt in the jaws

Accuracy per grasp = 1 − 5·|pos_esti − pos_real| / l (positions along the rod from its
geometric centre). Every grasp is estimated twice from the same measurement: ours (estimator
`{trial["estimator"]}`, a second pose rolled by {trial["roll_deg"]}°) and the paper's method
({report.paper.METHOD}: the vertical line through the CoM from one static pose, met with the
rod's axis), so the two meet grasp by grasp in our world. The paper's published values (read
off its figure; obj1 and obj6 only) stand beside. Rows: bins of the tilt in the jaws, 0–90°
from level. Figure: one panel per object; lines are bin means with the 95 % t interval of the
mean (Student's t, n − 1 degrees of freedom; none for a bin of one grasp), broken where a bin
is empty.

![accuracy](accuracy.png)

{report.accuracy_table(acc)}

### Against the paper and the aims

{report.accuracy_verdict(acc)}

### Ours against the paper's method, measured in our world

{report.method_comparison(acc)}

### The wrist force/torque sensor instead of the joint torques

The same grasps, poses and side views; the CoM from the wrist sensor's wrench (a strain-gauge
sensor between flange and gripper, this preset's class: docs/design.md, "Realistic sensing")
averaged over the same windows as the joint torques, and from both stacked.

{report.wrist_sensor_table(acc)}

## Calibration: is each estimate's stated uncertainty right?

Each grasp states the standard deviation of its estimate along the rod (`pos_std_m`, from
every error source the robot can know). If it is right, z = (pos_esti − pos_real) / pos_std
follows N(0, 1): 68.3 % of the grasps within ±1σ, 95 % within ±1.96σ, rms z 1. The paper's
six objects pooled here; each extra object in its own section.

"""


def _regrasp_part(acc: list, reg: list) -> str:
    """Experiment 2 (pick and place), the extra pose, the extra objects."""
    title = (
        "Experiment 2: pick-and-place success, regrasp planner against the geometric-centre grasp"
    )
    return f"""## {title}

Success = the rod ends inside the drop box; baseline and regrasp see the same scenes. In
brackets: successes/trials and the 95 % Wilson interval (%).

![regrasp](regrasp.png)

{report.regrasp_table(reg)}

{report.regrasp_verdict(reg)}

### The extra measurement pose

{report.extra_pose_summary(reg)}

## Extra objects, beyond the paper

{report.extra_objects_section(acc, reg)}

"""


def _settings_part(noise: float, settings: dict, versions: dict) -> str:
    """The settings that the numbers above depend on, and the software's versions."""
    trial = settings["trial"]
    return f"""## Settings

- torque sensor: white noise σ = {noise} N·m per sample at {1 / settings["world"]["sim_dt"]:.0f} Hz
  (averaged over {trial["window"]} s after {trial["settle"]} s of settling), τ_before
  {trial["tau_before"]}; estimator `{trial["estimator"]}`
- grip force {settings["motion"]["grip_force"]} N per finger; pad friction
  {settings["world"]["pad_friction"]} (sliding, torsional, rolling), condim
  {settings["world"]["pad_condim"]}; noslip iterations {settings["world"]["noslip_iterations"]}
- measurement {trial["lift_height"]} m above the table; regrasp when the tilt exceeds
  {settings["regrasp"]["slip_tilt_deg"]} deg or the CoM lies more than
  {settings["regrasp"]["max_com_offset"]} m from the jaws
- software: {", ".join(f"{k} {v}" for k, v in versions.items())}

Raw data: `accuracy.csv`, `regrasp.csv`; every setting: `run.json`.
"""
