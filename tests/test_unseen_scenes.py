"""The top view on scenes the project never built: within the bounds of a rod there, or refused.

Real renders (MuJoCo, headless EGL) of scenes built apart from the workcell
(``benchmarks/unseen/scenes.py``): other tables, cameras, light, rods and clutter; each judged
against the scene as built, clean and with the realistic preset's depth noise. A subset of
``unseen.families`` (the whole set: benchmarks/unseen_scenes.py). Not here: the
family ``end_on`` (a second object touching the rod's end on its axis), which from above is
one rod with a head, as the project's own rods are (reported by the benchmark).
"""

import sys
from pathlib import Path

import pytest

sys.path.append(str(Path(__file__).resolve().parents[1] / "benchmarks"))
from unseen import families as uf  # noqa: E402  (benchmarks/unseen/)

SUBSET = {
    "table_colour": None,  # None: every scene of the family
    "camera_height": ("1.05m_obj2", "1.15m_obj4", "1.35m_obj2", "1.45m_obj4"),
    "camera_tilt_small": None,
    "light": ("dim_obj2", "bright_obj4", "warm_obj2", "blue_obj4", "spot_obj2"),
    "rod_shapes": None,
    "second_rod_parallel": (
        "same_0mm",
        "same_1mm",
        "same_3mm",
        "thin_shifted_0mm",
        "thin_shifted_2mm",
        "hammer_and_cylinder_touching",
        "shorter_alongside",
        "thin_shorter_alongside",
    ),  # fmt: skip
    "second_rod_touching": None,
    "second_rod_crossing": None,
    "clutter_box": ("box_at_side_obj2", "box_at_side_cylinder"),
    "clutter_cable": ("crossing_cylinder", "along_obj2"),
}
# Scenes perception is meant to measure: at least this share of their views right.
MIN_RIGHT = {"clean": 1.0, "realistic": 0.85}


@pytest.fixture(scope="module")
def outcomes():
    """(scene, depth label, judged outcome) over the subset."""
    rows = []
    for k, scene in enumerate(uf.families()):
        names = SUBSET.get(scene.family, ())
        if names is not None and scene.name not in names:
            continue
        for label, judged in uf.top_view_outcome(scene, noise_seed=k).items():
            rows.append((scene, label, judged))
    return rows


def test_the_subset_is_what_it_says(outcomes):
    families = {scene.family for scene, _, _ in outcomes}
    assert families == set(SUBSET)
    assert len(outcomes) >= 70


def test_no_view_gives_a_rod_that_fits_no_rod_in_the_scene(outcomes):
    wrong = [(s.family, s.name, label, j) for s, label, j in outcomes if j["outcome"] == "wrong"]
    assert wrong == []


def test_the_rods_measured_are_within_the_bounds(outcomes):
    """Right answers hold the bounds (the judge's, restated: the test fails if it loosens)."""
    for scene, label, judged in outcomes:
        if judged["outcome"] == "right":
            bound = 4.5 if label == "realistic" else 3.0
            assert judged["centre_mm"] <= bound and judged["yaw_deg"] <= 1.0, (scene, judged)
            assert abs(judged["length_mm"]) <= 8.0, (scene, judged)


@pytest.mark.parametrize("label", uf.DEPTHS)
def test_scenes_it_should_measure_are_measured(outcomes, label):
    """Another table colour, the camera moved, other light, other rods: measured, not
    refused (refusing everything would pass the tests above)."""
    views = [(s, j) for s, lab, j in outcomes if lab == label and s.should_measure]
    right = [s.name for s, j in views if j["outcome"] == "right"]
    assert len(views) >= 25
    assert len(right) >= MIN_RIGHT[label] * len(views), [
        (s.family, s.name, j) for s, j in views if j["outcome"] != "right"
    ]


def test_two_rods_lying_against_each_other_are_refused(outcomes):
    """The issue's silent error: two rods against each other measured as one between them;
    and a shorter one alongside over two thirds, measured as the longer (issue 44)."""
    touching = ("same_0mm", "same_1mm", "thin_shifted_0mm", "hammer_and_cylinder_touching",
                "shorter_alongside", "thin_shorter_alongside")  # fmt: skip
    views = [(s.name, label, j) for s, label, j in outcomes if s.name in touching]
    assert len(views) == 2 * len(touching)
    assert all(j["outcome"] == "refused" for _, _, j in views), views
