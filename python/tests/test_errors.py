"""Bad input from Python: one clear exception each, naming the input."""

import numpy as np
import pytest

import hovs
from conftest import run_hovs


def test_error_is_a_value_error():
    assert issubclass(hovs.Error, ValueError)


def test_missing_and_foreign_files(tmp_path, dataset):
    with pytest.raises(hovs.Error, match="nope.json: .*not found"):
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


def test_the_module_checks_memory_as_the_cli_does(tmp_path, dataset):
    """A layout whose views would take more memory than the machine has is refused at once (it once ran on)."""
    layout = tmp_path / "huge.yaml"
    views = "".join(
        f"  - {{name: v{k}, type: cylindrical, width: 32768, height: 32768, elevation_min: -60, elevation_max: 0,"
        f" azimuth_centre: 0, azimuth_span: 360}}\n" for k in range(12))
    layout.write_text("name: huge\nviews:\n" + views)
    cam = hovs.Dataset(str(dataset)).camera()
    with pytest.raises(hovs.Error, match="GB of memory"):
        hovs.Unwrapper(cam, str(layout))


def test_ground_truth_of_another_size_and_non_finite_poses(tmp_path, dataset, source_dir):
    """The module refuses what the CLI refuses: a ground-truth EXR of another size than its image, a pose with NaN."""
    import json
    import shutil
    copy = tmp_path / "copy"
    shutil.copytree(dataset.parent, copy)
    manifest = json.loads((copy / "dataset.json").read_text())
    frame = manifest["frames"][0]
    exr = frame["views"][0]["ground_truth"]["exr"]
    # An EXR of another size under the frame's name, its checksum made to match (a consistent but wrong file).
    other = tmp_path / "other"
    run_hovs("dataset", "--scene", source_dir / "scenes" / "reference_calibration.yaml", "--downscale", 10,
             "--samples", 1, "-n", 1, "--out", other)
    other_manifest = json.loads((other / "dataset.json").read_text())
    shutil.copyfile(other / other_manifest["frames"][0]["views"][0]["ground_truth"]["exr"], copy / exr)
    checksum = fnv1a64_checksum(copy / exr)
    frame["checksums"][exr] = checksum
    (copy / "dataset.json").write_text(json.dumps(manifest))
    d = hovs.Dataset(str(copy / "dataset.json"))
    with pytest.raises(hovs.Error, match="the ground truth is 275 x 220 but its image"):
        d.ground_truth(frame["id"])
    pose = np.eye(4)
    pose[0, 3] = np.nan
    with pytest.raises(hovs.Error, match=r"right_from_left.*not a finite number"):
        hovs.triangulate(np.array([[0, 0, 1.0]]), np.array([[0, 0, 1.0]]), pose)


def fnv1a64_checksum(path):
    """FNV-1a 64 of a file, as hovs writes it (core/io.h FileChecksum)."""
    h = 14695981039346656037
    for b in path.read_bytes():
        h = ((h ^ b) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return f"fnv1a64:{h:016x}"
