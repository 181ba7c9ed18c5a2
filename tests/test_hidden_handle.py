"""A mallet whose handle a structured-light camera's depth cannot see is refused, not
measured as its head.

MuJoCo renders of the failure-mode family's mallets (``benchmarks/unseen/real_failures.py``:
a 4 x 9 cm head on a 24 cm handle 7 or 9 mm high) seen by a structured-light camera at
1.25 m (its depth noise, holes and the projector's shadow), over several draws of the
noise. Before, in 2 of these draws the 7 mm handle was lost and the head alone came out
as a 9 cm rod across the tool (a confident wrong answer, with or without colour). Each
answer, with and without the colour image, is right or refused, never wrong (issue 34's
bounds), and the same in the fitted table's frame as in the world's (issue 44).
"""

import sys
from pathlib import Path

import pytest

sys.path.append(str(Path(__file__).resolve().parents[1] / "benchmarks"))
from unseen import real_failures as rf  # noqa: E402  (benchmarks/unseen/)

MALLETS = ("mallet_7mm_high_structured_light_shadow", "mallet_9mm_structured_light_shadow")
DRAWS = (7000, 7013, 7026, 7039)  # noise seeds (benchmarks' sweep: 7000 + 13 k)


@pytest.fixture(scope="module")
def answers():
    """(frame, noise seed, the outcomes) for each mallet and draw."""
    frames = [f for f in rf.frames(0) if f.parameter in MALLETS]
    renders = rf._Renders()
    # (*DRAWS, and the benchmark's own draw: for the 7 mm mallet, the one whose answer
    # differed in the table's frame before, the table edge's smear 13 cm beyond the handle's
    # end taken for the tool dipping over it)
    return [(f.parameter, seed, rf.run_frame(f, renders, seed)) for f in frames
            for seed in (*DRAWS, rf.noise_seed(f))]  # fmt: skip


def test_the_mallets_are_never_measured_wrong(answers):
    assert len(answers) == len(MALLETS) * (len(DRAWS) + 1)
    for name, seed, judged in answers:
        for label, outcome in (("with colour", judged), ("depth alone", judged["depth_alone"])):
            assert outcome["outcome"] != "wrong", (name, seed, label, outcome)


def test_a_head_alone_is_refused_as_a_head_whose_handle_is_not_seen(answers):
    """From the depth alone, a head measured without its handle is refused as such."""
    why = [j["depth_alone"].get("why", "") for _, _, j in answers]
    assert any("a tool's head whose handle is not seen" in w for w in why), why


def test_the_answers_are_the_same_in_the_table_frame(answers):
    for name, seed, judged in answers:
        assert all(judged["same_in_table_frame"].values()), (name, seed, judged)
