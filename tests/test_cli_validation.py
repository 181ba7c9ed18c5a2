"""Bad command lines end before anything runs: exit status 2, one clear message, no
traceback, nothing written (issue 15)."""

import subprocess
import sys

import pytest

from comgrasp_pin.cli import main

BAD = [
    (["--trials", "0"], "--trials: must be an integer >= 1 and <= 1000, got 0"),
    (["--trials", "-3"], "--trials: must be an integer >= 1 and <= 1000, got -3"),
    (["--trials", "2.5"], "--trials: must be an integer, got '2.5'"),
    (["--trials", "1001"], "--trials: must be an integer >= 1 and <= 1000, got 1001"),
    (["--objects", ""], "--objects: needs comma-separated names"),
    (["--objects", "obj1,,obj2"], "--objects: needs comma-separated names"),
    (["--objects", "obj1,obj1"], "['obj1'] are listed more than once"),
    (["--objects", "obj9"], "unknown object(s) ['obj9']"),
    (["--noise", "-0.05"], "--noise: must be >= 0.0, got -0.05"),
    (["--noise", "nan"], "--noise: must be finite, got nan"),
    (["--noise", "inf"], "--noise: must be finite, got inf"),
    (["--noise", "loud"], "--noise: must be a number, got 'loud'"),
    (["--seed", "-1"], "--seed: must be an integer >= 0, got -1"),
    (["--workers", "-2"], "--workers: must be an integer >= 1, got -2"),
    (["--workers", "0"], "--workers: must be an integer >= 1, got 0"),
    (["--resume", "--overwrite"], "not allowed with argument"),
    (["--retry-failed", "--overwrite"], "--retry-failed continues a run, --overwrite starts"),
    (["--estimator", "magic"], "invalid choice: 'magic'"),
    (["--backend", "spark"], "invalid choice: 'spark'"),
    (["--ray-address", "auto"], "--ray-address is for --backend ray"),
]


def _run(argv, capsys) -> tuple[int, str]:
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's exit
        code = exc.code
    err = capsys.readouterr().err
    return code, err


@pytest.mark.parametrize("command", ["accuracy", "regrasp", "reproduce"])
@pytest.mark.parametrize(("args", "message"), BAD)
def test_bad_arguments_exit_2_with_one_message_and_write_nothing(
    tmp_path, capsys, command, args, message
):
    out = tmp_path / "run"
    code, err = _run([command, "--out", str(out), *args], capsys)
    assert code == 2
    assert message in err
    assert "Traceback" not in err
    assert len([line for line in err.splitlines() if "error:" in line]) == 1
    assert not out.exists()


def test_out_pointing_at_a_file_is_refused(tmp_path, capsys):
    target = tmp_path / "a_file"
    target.write_text("keep me")
    for out in (target, target / "below"):
        code, err = _run(["accuracy", "--out", str(out), "--objects", "obj1"], capsys)
        assert code == 2 and f"{target} exists and is not a folder" in err
        assert "Traceback" not in err
    assert target.read_text() == "keep me"
    code, err = _run(["accuracy", "--out", ""], capsys)
    assert code == 2 and "--out: must name a folder, got an empty path" in err


@pytest.mark.parametrize("command", ["demo", "views", "scene"])
def test_other_commands_check_their_seed_and_out(tmp_path, capsys, command):
    code, err = _run([command, "--seed", "-1", "--out", str(tmp_path / "x")], capsys)
    assert code == 2 and "--seed: must be an integer >= 0, got -1" in err
    (tmp_path / "f").write_text("")
    code, err = _run([command, "--out", str(tmp_path / "f")], capsys)
    assert code == 2 and "exists and is not a folder" in err
    assert not (tmp_path / "x").exists()


def test_the_installed_command_prints_no_traceback(tmp_path):
    target = tmp_path / "file"
    target.write_text("")
    result = subprocess.run(
        [sys.executable, "-m", "comgrasp_pin.cli", "accuracy", "--out", str(target)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 2
    assert "Traceback" not in result.stderr and "is not a folder" in result.stderr


_WITHOUT_RAY = """
import sys
sys.modules["ray"] = None  # as if ray were not installed: `import ray` raises ImportError
from comgrasp_pin.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize("command", ["accuracy", "sweep"])
def test_backend_ray_without_ray_installed_exits_2_saying_how_to_install_it(tmp_path, command):
    args = [command, "--backend", "ray", "--objects", "obj1", "--trials", "1",
            "--out", str(tmp_path / "x")]  # fmt: skip
    if command == "sweep":
        args += ["--param", "grip_force=10,15"]
    result = subprocess.run([sys.executable, "-c", _WITHOUT_RAY, *args], capture_output=True,
                            text=True, check=False)  # fmt: skip
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert "--backend ray needs Ray, which is not installed" in result.stderr
    assert "pip install 'comgrasp_pin[ray]'" in result.stderr
    assert not (tmp_path / "x").exists()
