"""hovs.Camera against the CLI's outputs: the renderer's exact corner pixels, the calibration's files, and OpenCV's
own omnidir projection of the YAML file hovs writes."""

import cv2
import numpy as np
import pytest

import hovs


def annulus_pixels(cam, n=2000, seed=7):
    """Pixels spread over the image, kept where the model is valid."""
    rng = np.random.default_rng(seed)
    px = rng.uniform([0, 0], [cam.width - 1, cam.height - 1], size=(n, 2))
    rays, valid = cam.unproject(px)
    return px[valid], rays[valid]


def test_exact_rig_projects_the_renderers_corners(dataset):
    data = hovs.Dataset(str(dataset))
    cam = data.camera()
    assert cam.kind == "exact" and (cam.width, cam.height) == (550, 440)
    for frame in data.frames:
        c = data.corners(frame)
        assert len(c["ids"]) > 20
        # Each corner's bearing from the viewpoint is that of its reflection point on the mirror (single viewpoint).
        uv, valid = cam.project(c["mirror_points"])
        assert valid.all()
        assert np.abs(uv - c["pixels"]).max() < 1e-6
        # The same from the world points brought into the mirror frame.
        world_from_mirror = data.world_from_mirror()
        R, t = world_from_mirror[:3, :3], world_from_mirror[:3, 3]
        mirror_points = (c["world"] - t) @ R
        uv2, valid2 = cam.project(mirror_points)
        assert valid2.all() and np.abs(uv2 - c["pixels"]).max() < 1e-6
        rays, ok = cam.unproject(c["pixels"])
        assert ok.all()
        expected = mirror_points / np.linalg.norm(mirror_points, axis=1, keepdims=True)
        assert np.abs(rays - expected).max() < 1e-8


@pytest.mark.parametrize("model", ["polynomial", "unified"])
def test_round_trip(calibration, model):
    path = calibration / ("calibration.json" if model == "polynomial" else "unified.yaml")
    cam = hovs.load_camera(str(path), model="polynomial") if model == "polynomial" else hovs.load_camera(str(path))
    assert cam.kind == model
    px, rays = annulus_pixels(cam)
    assert len(px) > 500
    np.testing.assert_allclose(np.linalg.norm(rays, axis=1), 1, atol=1e-12)
    distances = np.random.default_rng(1).uniform(0.5, 20, size=(len(rays), 1))
    uv, valid = cam.project(rays * distances)
    assert valid.all()
    assert np.abs(uv - px).max() < 0.02  # the polynomial's inverse is fitted to 0.01 px


def test_ocamcalib_file_matches_calibration_json(calibration):
    """calib_results.txt (6 decimals, as OCamCalib writes it) and calibration.json give the same pixels."""
    exact = hovs.load_camera(str(calibration / "calibration.json"), model="polynomial")
    txt = hovs.load_camera(str(calibration / "calib_results.txt"))
    assert txt.kind == "polynomial"
    _, rays = annulus_pixels(exact)
    a, va = exact.project(rays)
    b, vb = txt.project(rays)
    both = va & vb
    assert both.mean() > 0.98
    assert np.abs(a[both] - b[both]).max() < 0.05


def test_opencv_omnidir_reads_the_unified_yaml(calibration):
    """cv2.omnidir.projectPoints with K, D and xi as cv2.FileStorage reads them from hovs' file."""
    path = str(calibration / "unified.yaml")
    cam = hovs.load_camera(path)
    fs = cv2.FileStorage(path, cv2.FILE_STORAGE_READ)
    K, D = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat()
    xi_node = fs.getNode("xi")
    xi = xi_node.real() if xi_node.isReal() else float(xi_node.mat()[0, 0])
    _, rays = annulus_pixels(cam)
    points = rays * 3.0
    uv, valid = cam.project(points)
    # omnidir's camera frame is (x, y, -z) of hovs' mirror frame.
    cv_points = (points * [1, 1, -1]).reshape(-1, 1, 3).astype(np.float64)
    cv_uv, _ = cv2.omnidir.projectPoints(cv_points, np.zeros(3), np.zeros(3), K, float(xi), D)
    assert valid.all()
    assert np.abs(cv_uv.reshape(-1, 2) - uv).max() < 1e-6


@pytest.mark.parametrize("model", ["polynomial", "unified"])
def test_jacobian_matches_finite_differences(calibration, model):
    path = calibration / ("calibration.json" if model == "polynomial" else "unified.yaml")
    cam = hovs.load_camera(str(path), model="polynomial") if model == "polynomial" else hovs.load_camera(str(path))
    _, rays = annulus_pixels(cam, n=200)
    points = rays * 2.0
    J, uv, valid = cam.project_jacobian(points)
    assert valid.all() and J.shape == (len(points), 2, 3)
    h = 1e-6
    for k in range(3):
        step = np.zeros(3)
        step[k] = h
        plus, _ = cam.project(points + step, bounded=False)
        minus, _ = cam.project(points - step, bounded=False)
        numeric = (plus - minus) / (2 * h)
        assert np.abs(J[:, :, k] - numeric).max() < 1e-3 * np.abs(J).max()


def test_single_rows_and_invalid_inputs(calibration):
    cam = hovs.load_camera(str(calibration / "unified.yaml"))
    px, rays = annulus_pixels(cam, n=50)
    uv, valid = cam.project(rays[0])
    assert uv.shape == (2,) and valid.shape == () and bool(valid)
    uv, valid = cam.project([[0.0, 0.0, 0.0], [np.nan, 0, 0]])
    assert not valid.any() and np.isnan(uv).all()
    rays, valid = cam.unproject([[-100.0, -100.0]])
    assert not valid[0] and np.isnan(rays).all()
    # Integer and float32 arrays are read as float64.
    uv32, _ = cam.project(np.asarray(rays[:0], dtype=np.float32))
    assert uv32.shape == (0, 2)


def test_parameters(calibration):
    poly = hovs.load_camera(str(calibration / "calibration.json"), model="polynomial").parameters
    assert {"cx", "cy", "c", "d", "e", "poly", "inv_poly", "rho_min", "rho_max"} <= poly.keys()
    uni = hovs.load_camera(str(calibration / "unified.yaml")).parameters
    assert {"xi", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"} <= uni.keys()


def test_the_omnidir_samples_own_file(calibration, tmp_path):
    """OpenCV's omni_calibration sample writes XML by default, xi as a number and no image size."""
    yaml_path = str(calibration / "unified.yaml")
    cam = hovs.load_camera(yaml_path)
    fs = cv2.FileStorage(yaml_path, cv2.FILE_STORAGE_READ)
    K, D, xi = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat(), fs.getNode("xi")
    assert xi.isReal(), "xi is written as the sample writes it: a plain number"
    out = cv2.FileStorage(str(tmp_path / "out_camera_params.xml"), cv2.FILE_STORAGE_WRITE)
    out.write("calibration_time", "Sat Dec  5 12:00:00 2026")
    out.write("nFrames", 1)
    out.write("flags", 0)
    out.write("camera_matrix", K)
    out.write("distortion_coefficients", D)
    out.write("xi", xi.real())
    out.write("extrinsic_parameters", np.array([[0.1, 0.2, 0.3, 0.0, 0.1, 0.5]]))
    out.write("rms", 0.4)
    out.release()
    with pytest.raises(hovs.Error, match="has no image_width / image_height"):
        hovs.load_camera(str(tmp_path / "out_camera_params.xml"))
    xml = hovs.load_camera(str(tmp_path / "out_camera_params.xml"), image_size=(cam.width, cam.height))
    _, rays = annulus_pixels(cam, n=300)
    a, va = cam.project(rays, bounded=False)
    b, vb = xml.project(rays, bounded=False)
    assert va.all() and vb.all() and np.abs(a - b).max() < 1e-9
