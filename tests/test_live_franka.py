"""`comgrasp live` against franky-sim: libfranka's protocol on 127.0.0.1, MuJoCo behind it.

Each test runs the command as a user would (a subprocess) on the simulated FR3, with a
payload of known mass, CoM and inertia that the simulator attaches between the runs. The
truth is the simulator's body; the estimate comes from the torques the robot reports.
Tests connect only to the loopback address. Skipped where the franka extra is missing.
"""

import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from comgrasp_pin.estimation.trust import t_quantile

pytest.importorskip("franky", reason='the franka extra is missing: pip install ".[franka]"')
pytest.importorskip("franky_sim", reason='the franka extra is missing: pip install ".[franka]"')

MASS, COM = 1.1, np.array([0.03, -0.04, 0.05])  # kg; m, flange frame
MOMENTS = (4e-3, 5e-3, 6e-3)  # kg m^2, the flange's axes


def live(out, *args, timeout=300):
    """Run `comgrasp live --sim --yes --out OUT ARGS` to the end."""
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", "live", "--out", str(out), *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)  # fmt: skip


def no_traceback(res):
    assert "Traceback" not in res.stderr, res.stderr


@pytest.fixture(scope="module")
def identified(tmp_path_factory):
    out = tmp_path_factory.mktemp("live")
    spec = ",".join(f"{v:g}" for v in (MASS, *COM, *MOMENTS))
    res = live(out, "--sim", "--yes", "--set-load", "--sim-payload", spec)
    return res, out


def test_a_payload_is_identified_and_its_load_set(identified):
    res, out = identified
    assert res.returncode == 0, res.stderr
    r = json.loads((out / "RESULT.json").read_text())
    assert r["verdict"] == "identified"
    mass, com = r["mass_kg"], np.array(r["com_m"])
    # 20 payloads (benchmarks/live_franka.py): mass within 0.42 %, CoM within 1.9 mm; the
    # issue's targets (2 %, 5 mm) here, the intervals below the sharp check
    assert abs(mass - MASS) < 0.02 * MASS
    assert np.linalg.norm(com - COM) < 5e-3
    # the truth within its 99.9 % interval (Student's t of the stated dof): 1 in 1000 fails
    dof = [r["dof"]["mass"], *r["dof"]["com"]]
    dof = np.array([np.inf if d is None else d for d in dof], dtype=float)
    q999 = np.array([t_quantile(d, 0.999) for d in dof])
    std = np.array([r["std"]["mass_kg"], *r["std"]["com_m"]])
    assert np.all(np.abs(np.r_[mass, com] - np.r_[MASS, COM]) < q999 * std)
    info = json.loads((out / "live.json").read_text())
    sent = info["set_load"]
    assert sent["agrees"] and sent["sent"]["mass"] == pytest.approx(mass)
    assert sent["read_back"]["m_load"] == pytest.approx(mass, abs=1e-4)
    np.testing.assert_allclose(sent["read_back"]["F_x_Cload"], com, atol=1e-4)
    assert info["complete"] and info["wall_time_s"] < 120


def test_the_live_log_estimated_offline_gives_the_same_numbers(identified):
    _, out = identified
    info = json.loads((out / "live.json").read_text())
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", *info["offline"].split()[1:]]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    live_result = json.loads((out / "RESULT.json").read_text())
    offline = json.loads((out / "RESULT_offline.json").read_text())
    assert offline == live_result


def test_an_empty_arm_gets_no_load(tmp_path):
    res = live(tmp_path, "--sim", "--yes", "--set-load", "--n-poses", "2")
    no_traceback(res)
    assert res.returncode == 2
    # the estimator refuses a mass within 3 std of zero (EmptyGripperError), or the
    # verdict is nothing held
    assert "is the gripper empty" in res.stderr or "nothing held" in res.stderr
    assert "Nothing was sent" in res.stderr
    info = json.loads((tmp_path / "live.json").read_text())
    assert info["complete"] and "set_load" not in info


def test_a_payload_too_light_to_tell_is_never_set_wrong(tmp_path):
    """3 g: nothing held (no load sent), or identified with the truth in its 99.9 %
    interval (Student's t of the stated dof: 1 in 1000 fails; the 95 % one misses 1 in 20,
    as it should)."""
    res = live(tmp_path, "--sim", "--yes", "--set-load", "--n-poses", "2",
               "--sim-payload", "0.003,0.0,0.0,0.05")  # fmt: skip
    no_traceback(res)
    info = json.loads((tmp_path / "live.json").read_text())
    if not (tmp_path / "RESULT.json").exists():  # refused by the estimator: nothing held
        assert res.returncode == 2 and "set_load" not in info
        return
    r = json.loads((tmp_path / "RESULT.json").read_text())
    if r["verdict"] == "identified":
        dof = r["dof"]["mass"]
        q999 = t_quantile(np.inf if dof is None else dof, 0.999)
        assert abs(r["mass_kg"] - 0.003) < q999 * r["std"]["mass_kg"] and res.returncode == 0
    else:
        assert res.returncode == 2 and "set_load" not in info


def test_a_refused_connection_is_a_clear_error(tmp_path):
    res = live(tmp_path, "--host", "127.0.0.1", "--yes", timeout=60)
    no_traceback(res)
    assert res.returncode == 2
    assert "cannot connect to a Franka at 127.0.0.1" in res.stderr


def test_a_robot_reporting_errors_is_not_moved(tmp_path):
    res = live(tmp_path, "--sim", "--yes", "--sim-fault", "reflex", timeout=120)
    no_traceback(res)
    assert res.returncode == 2
    assert "reports errors" in res.stderr and "joint_reflex" in res.stderr
    assert not (tmp_path / "live_log.csv").exists()


def test_a_lost_connection_keeps_what_was_recorded(tmp_path):
    res = live(tmp_path, "--sim", "--yes", "--sim-lose-after", "6", timeout=120)
    no_traceback(res)
    assert res.returncode == 2
    assert "ended early" in res.stderr
    info = json.loads((tmp_path / "live.json").read_text())
    assert not info["complete"] and info["n_readings"] > 100
    assert (tmp_path / "live_log.csv").stat().st_size > 0


def test_ctrl_c_stops_the_arm_and_keeps_the_log(tmp_path):
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", "live", "--sim", "--yes",
           "--out", str(tmp_path)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            stdin=subprocess.DEVNULL)  # fmt: skip
    time.sleep(12)  # the sim starts (a few s), the arm moves
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert "Traceback" not in err, err
    assert proc.returncode == 2
    assert "interrupted (Ctrl-C): the arm was stopped" in err
    info = json.loads((tmp_path / "live.json").read_text())
    assert not info["complete"] and info["n_readings"] > 0


def test_a_dry_run_shows_the_plan_and_moves_nothing(tmp_path):
    res = live(tmp_path, "--sim", "--dry-run", timeout=120)
    assert res.returncode == 0, res.stderr
    assert "pose 3:" in res.stdout and "dry run: nothing moved" in res.stdout
    assert not (tmp_path / "live_log.csv").exists()


def test_nothing_moves_unconfirmed(tmp_path):
    res = live(tmp_path, "--sim", timeout=120)  # stdin is not a terminal, no --yes
    no_traceback(res)
    assert res.returncode == 2 and "give --yes" in res.stderr
    assert not (tmp_path / "live_log.csv").exists()


def test_the_dynamics_factor_is_capped(tmp_path):
    res = live(tmp_path, "--sim", "--yes", "--dynamics-factor", "0.8", timeout=60)
    no_traceback(res)
    assert res.returncode == 2 and "--dynamics-factor 0.8: must be in (0, 0.3]" in res.stderr


@pytest.fixture(scope="module")
def motion_file(tmp_path_factory):
    """A short excitation motion for the FR3 at the sim's pose, slow enough for factor 0.2."""
    from comgrasp_pin._paths import fr3_urdf

    out = tmp_path_factory.mktemp("motion") / "motion.json"
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", "plan-motion", "--urdf", str(fr3_urdf()),
           "--ee-frame", "fr3_link8", "--start", "0,0,0,-1.5708,0,1.5708,0.7854",
           "--duration", "8", "--velocity-scale", "0.3", "--acceleration", "3",
           "--candidates", "200", "--starts", "1", "--out", str(out)]  # fmt: skip
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    return out


def test_a_payload_is_identified_along_a_planned_motion(tmp_path, motion_file):
    """franky-sim runs in real time, so no two sessions are the same: on a busy machine a
    session can be several times noisier than at idle (a CI run: mass std 4.2 % instead of
    about 1 %, the truth 1.7 std off) or refused (its halves 3.1 std apart). Every session
    that identifies must hold the truth within its interval (never a confident wrong
    answer); one of two sessions must also be as precise as the benchmark's at idle."""
    spec = ",".join(f"{v:g}" for v in (MASS, *COM, *MOMENTS))
    precise = []
    for attempt in range(2):
        out = tmp_path / f"session{attempt}"
        res = live(out, "--sim", "--yes", "--set-load", "--motion", str(motion_file),
                   "--sim-payload", spec)  # fmt: skip
        no_traceback(res)
        if res.returncode == 2 and "Nothing was sent to the robot" in res.stderr:
            continue  # refused by the trust rules: no load set, no answer
        assert res.returncode == 0, res.stderr
        r = json.loads((out / "RESULT.json").read_text())
        assert r["verdict"] == "identified" and r["mode"] == "a motion's joint torques"
        mass, com = r["mass_kg"], np.array(r["com_m"])
        std = np.array([r["std"]["mass_kg"], *r["std"]["com_m"]])
        assert np.all(np.abs(np.r_[mass, com] - np.r_[MASS, COM]) < 4.5 * std)
        info = json.loads((out / "live.json").read_text())
        assert info["set_load"]["agrees"] and info["motion"] == str(motion_file)
        # the same numbers offline, from the written log and windows
        cmd = [sys.executable, "-m", "comgrasp_pin.cli", *info["offline"].split()[1:]]
        off = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        assert off.returncode == 0, off.stderr
        assert json.loads((out / "RESULT_offline.json").read_text()) == r
        # 20 payloads (benchmarks/live_franka.py --motion): mass within 2.4 %, CoM within
        # 23 mm (benchmarks/README.md)
        precise.append(abs(mass - MASS) < 0.05 * MASS and np.linalg.norm(com - COM) < 30e-3)
        if precise[-1]:
            break
    assert any(precise), precise


def test_a_motion_dry_run_shows_it_and_moves_nothing(tmp_path, motion_file):
    res = live(tmp_path, "--sim", "--dry-run", "--motion", str(motion_file), timeout=120)
    assert res.returncode == 0, res.stderr
    assert "a planned motion for fr3_link8" in res.stdout and "waypoints" in res.stdout
    assert "dry run: nothing moved" in res.stdout
    assert not (tmp_path / "live_log.csv").exists()


def test_another_arms_motion_is_refused(tmp_path, motion_file):
    d = json.loads(motion_file.read_text())
    d["joint_names"] = [f"joint{i}" for i in range(7)]
    other = tmp_path / "other.json"
    other.write_text(json.dumps(d))
    res = live(tmp_path, "--sim", "--yes", "--motion", str(other), timeout=120)
    no_traceback(res)
    assert res.returncode == 2 and "not of this arm's" in res.stderr
    assert not (tmp_path / "live_log.csv").exists()


def test_an_arm_model_stands_for_the_empty_run(tmp_path, motion_file):
    """identify-arm on an empty run of the motion (the simulated FR3's own log), then a
    live run that attaches the payload first and plays the motion once: identified, within
    its intervals, the offline command (with --arm-model) gives the same numbers."""
    from comgrasp_pin._paths import fr3_urdf

    empty = live(tmp_path / "first", "--sim", "--yes", "--motion", str(motion_file),
                 "--sim-payload", "0.5,0,0,0.05")  # fmt: skip
    assert empty.returncode == 0, empty.stderr
    info = json.loads((tmp_path / "first" / "live.json").read_text())
    empty_window = info["offline"].split("--empty-window ")[1].split()[0]
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", "identify-arm", "--urdf", str(fr3_urdf()),
           "--ee-frame", "fr3_link8", "--csv", str(tmp_path / "first" / "live_log.csv"),
           "--window", empty_window, "--out", str(tmp_path / "ARM.json")]  # fmt: skip
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    spec = ",".join(f"{v:g}" for v in (MASS, *COM, *MOMENTS))
    res = live(tmp_path / "second", "--sim", "--yes", "--motion", str(motion_file),
               "--arm-model", str(tmp_path / "ARM.json"), "--sim-payload", spec)  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert "the arm's own from --arm-model" in res.stdout
    r = json.loads((tmp_path / "second" / "RESULT.json").read_text())
    mass, com = r["mass_kg"], np.array(r["com_m"])
    std = np.array([r["std"]["mass_kg"], *r["std"]["com_m"]])
    assert abs(mass - MASS) < 0.1 * MASS
    assert np.all(np.abs(np.r_[mass, com] - np.r_[MASS, COM]) < 4.5 * std)
    info = json.loads((tmp_path / "second" / "live.json").read_text())
    assert "--arm-model" in info["offline"] and "--empty-csv" not in info["offline"]
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", *info["offline"].split()[1:]]
    off = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert off.returncode == 0, off.stderr
    assert json.loads((tmp_path / "second" / "RESULT_offline.json").read_text()) == r


def test_an_arm_model_without_a_motion_is_refused(tmp_path):
    res = live(tmp_path, "--sim", "--yes", "--arm-model", "ARM.json", timeout=60)
    no_traceback(res)
    assert res.returncode == 2 and "give --motion too" in res.stderr
