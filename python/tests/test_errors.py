"""Bad input from Python: one clear exception each, naming the input."""

import numpy as np
import pytest

import hovs


def test_error_is_a_value_error():
    assert issubclass(hovs.Error, ValueError)


def test_missing_and_foreign_files(tmp_path, dataset):
    with pytest.raises(hovs.Error, match="nope.json: file not found"):
        hovs.load_camera(str(tmp_path / "nope.json"))
    image = next((dataset.parent / "images").iterdir())
    with pytest.raises(hovs.Error, match=str(image)):
        hovs.load_camera(str(image))
    with pytest.raises(hovs.Error, match="model.*expected auto, physical, polynomial or unified"):
        hovs.load_camera(str(dataset), model="fisheye")


def test_yaml_of_another_camera_model(tmp_path):
    """A Kalibr camchain of a pinhole camera is not a catadioptric model hovs projects with."""
    camchain = tmp_path / "camchain.yaml"
    camchain.write_text(
        "cam0:\n"
        "  camera_model: pinhole\n"
        "  intrinsics: [461.6, 460.3, 366.3, 249.0]\n"
        "  distortion_model: radtan\n"
        "  distortion_coeffs: [-0.27, 0.06, 0.0002, 0.00002]\n"
        "  resolution: [752, 480]\n"
    )
    with pytest.raises(hovs.Error, match=str(camchain)):
        hovs.load_camera(str(camchain))


def test_arrays_of_the_wrong_shape_or_dtype(dataset):
    cam = hovs.Dataset(str(dataset)).camera()
    with pytest.raises(hovs.Error, match=r"points: expected shape \(N, 3\) or \(3,\), got \(4, 2\)"):
        cam.project(np.zeros((4, 2)))
    with pytest.raises(TypeError, match="points: expected an array of real numbers"):
        cam.project(np.array([["a", "b", "c"]]))
    with pytest.raises(TypeError, match="pixels: expected an array of real numbers.*bool"):
        cam.unproject(np.zeros((3, 2), dtype=bool))
    with pytest.raises(hovs.Error, match=r"pixels: expected shape \(N, 2\)"):
        cam.unproject(np.zeros((2, 2, 2)))
    with pytest.raises(hovs.Error, match="project_jacobian needs a polynomial or unified model"):
        cam.project_jacobian(np.ones((1, 3)))
