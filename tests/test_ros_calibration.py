"""ROS camera_calibration YAML files in the dialects camera drivers write (issue 34, item 3).

ROS's camera_calibration_parsers (image_common, ``parse_yml.cpp``) reads K from
``camera_matrix.data``, D from ``distortion_coefficients.data`` and, where the file names no
``distortion_model``, assumes plumb_bob. Older drivers' files say ``camera_model:``. The two
real files are read from ../shared/realdata (never copied here); their K and D are compared
to the YAML parsed in this test, not by the code under test.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from comgrasp_pin.errors import CameraFileError, ComGraspError
from comgrasp_pin.perception.frames.camera_model import OPENCV_MODELS
from comgrasp_pin.perception.frames.rgbd_files import read_camera_info

ROOT = Path(__file__).resolve().parents[1]
ROS_FILES = ROOT.parent / "shared" / "realdata" / "rgbd" / "ros_calibration_files"
REAL = ("davi1055_project_cam_480p.yaml", "mekabot_pg2_800x600_calib.yml")
K = [600.0, 0.0, 320.0, 0.0, 610.0, 240.0, 0.0, 0.0, 1.0]
D5 = [0.1, -0.2, 0.001, 0.002, 0.0]


def _write(tmp_path, D=D5, **model) -> Path:
    """A camera_calibration YAML as a ROS driver writes it, with the model keys given."""
    fields = {"image_width": 640, "image_height": 480, "camera_name": "cam",
              "camera_matrix": {"rows": 3, "cols": 3, "data": K}, **model,
              "distortion_coefficients": {"rows": 1, "cols": len(D), "data": list(D)}}  # fmt: skip
    path = tmp_path / "calib.yaml"
    path.write_text(yaml.safe_dump(fields, sort_keys=False))
    return path


def _read(path):
    camera, _ = read_camera_info(path)
    return camera


def test_camera_model_is_a_synonym_of_distortion_model(tmp_path):
    camera = _read(_write(tmp_path, camera_model="plumb_bob"))
    assert camera.distortion_model == "plumb_bob" and camera.D.tolist() == D5
    same = _read(_write(tmp_path, camera_model="plumb_bob", distortion_model="Plumb_Bob"))
    assert same.distortion_model == "plumb_bob"


def test_no_model_with_five_coefficients_is_plumb_bob_as_ros_assumes(tmp_path):
    camera = _read(_write(tmp_path))
    assert camera.distortion_model == "plumb_bob" and camera.distorted
    assert camera.K.ravel().tolist() == K and (camera.width, camera.height) == (640, 480)


def test_no_model_and_no_distortion_is_a_pinhole(tmp_path):
    assert not _read(_write(tmp_path, D=[0.0] * 4)).distorted
    assert _read(_write(tmp_path, D=[])).distortion_model == "none"


def test_no_model_with_another_count_is_refused(tmp_path):
    with pytest.raises(CameraFileError, match="no distortion_model and 8 .*plumb_bob"):
        _read(_write(tmp_path, D=[0.1, 0.01, 0, 0, 0, 0, 0, 0]))


@pytest.mark.parametrize("key", ["distortion_model", "camera_model"])
def test_an_unknown_model_is_refused_with_the_valid_list(tmp_path, key):
    with pytest.raises(CameraFileError) as info:
        _read(_write(tmp_path, **{key: "ftheta"}))
    assert isinstance(info.value, ComGraspError)
    message = str(info.value)
    assert key in message and "'ftheta'" in message
    assert all(name in message for name in ("none", *OPENCV_MODELS))


def test_the_two_keys_disagreeing_is_refused(tmp_path):
    with pytest.raises(CameraFileError, match="disagree.*plumb_bob"):
        _read(_write(tmp_path, distortion_model="plumb_bob", camera_model="equidistant"))


def test_rows_times_cols_must_match_the_data(tmp_path):
    path = _write(tmp_path)
    path.write_text(path.read_text().replace("cols: 5", "cols: 4"))
    with pytest.raises(CameraFileError, match="4 .*5 numbers"):
        _read(path)


@pytest.mark.skipif(
    not ROS_FILES.is_dir(), reason=f"the real data is not here: {ROS_FILES} (../shared/realdata)"
)
@pytest.mark.parametrize("name", REAL)
def test_real_ros_calibration_files_read_as_ros_reads_them(name):
    raw = yaml.safe_load((ROS_FILES / name).read_text())
    K_ros = np.array(raw["camera_matrix"]["data"], float).reshape(3, 3)  # row-major
    d = raw["distortion_coefficients"]
    D_ros = np.array(d["data"], float)[: d["rows"] * d["cols"]]
    camera = _read(ROS_FILES / name)
    assert (camera.width, camera.height) == (raw["image_width"], raw["image_height"])
    assert np.array_equal(camera.K, K_ros) and np.array_equal(camera.D, D_ros)
    assert camera.distortion_model == "plumb_bob" and len(camera.D) == 5 and camera.distorted
