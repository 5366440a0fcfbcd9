"""`hovs export --to equirect`: every valid pixel's range along its equirectangular ray, placed in the world by the
exported pose, is a point the renderer saw, and the image is the frame's view."""

import json

import cv2
import numpy as np
import pytest

import hovs

from conftest import run_hovs


def test_equirect_export_geometry(dataset, tmp_path):
    out = tmp_path / "equirect"
    run_hovs("export", "--dataset", dataset, "--to", "equirect", "--width", 512, "--out", out)
    poses = json.loads((out / "poses.json").read_text())
    assert poses["width"] == 512 and poses["height"] == 256
    data = hovs.Dataset(str(dataset))
    cam = data.camera()
    assert len(poses["frames"]) == len(data.frames)
    H, W = 256, 512
    v, u = np.mgrid[0:H, 0:W].astype(float)
    az = np.radians(180 - 360 * (u + 0.5) / W)
    el = np.radians(90 - 180 * (v + 0.5) / H)
    bearings = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], -1).reshape(-1, 3)
    for entry in poses["frames"][:2]:
        unit = entry["units"][data.units[0]]
        mask = cv2.imread(str(out / unit["mask"]), cv2.IMREAD_GRAYSCALE).reshape(-1) > 0
        rng = cv2.imread(str(out / unit["range"]), cv2.IMREAD_UNCHANGED)
        assert np.array_equal(rng, hovs.read_exr(str(out / unit["range"]))["Y"]), "OpenCV reads the range"
        rgb = cv2.imread(str(out / unit["rgb"]))
        assert rgb.shape == (H, W, 3) and mask.mean() > 0.2
        z = (rng if rng.ndim == 2 else rng[:, :, 0]).reshape(-1)
        assert np.all(z[~mask] == 0) and np.all(z[mask] >= 0)
        # The pixel's ray reaches the source image where the nearest source pixel's ground truth was taken: its
        # world point, seen from the pose, lies along the exported ray at the exported range (to the spread of
        # one source pixel).
        truth = data.ground_truth(entry["id"])
        src, ok = cam.project(bearings[mask])
        assert ok.all()
        iu, iv = np.round(src[:, 0]).astype(int), np.round(src[:, 1]).astype(int)
        world = np.stack([truth["P.X"][iv, iu], truth["P.Y"][iv, iu], truth["P.Z"][iv, iu]], -1)
        q, t = np.array(unit["world_from_mirror"]["q"]), np.array(unit["world_from_mirror"]["t"])
        w, x, y, zq = q
        R = np.array([[1 - 2 * (y * y + zq * zq), 2 * (x * y - zq * w), 2 * (x * zq + y * w)],
                      [2 * (x * y + zq * w), 1 - 2 * (x * x + zq * zq), 2 * (y * zq - x * w)],
                      [2 * (x * zq - y * w), 2 * (y * zq + x * w), 1 - 2 * (x * x + y * y)]])
        seen = (world - t) @ R  # mirror frame
        finite = np.isfinite(seen).all(axis=1) & (z[mask] > 0)
        assert finite.mean() > 0.5
        assert np.allclose(np.linalg.norm(seen[finite], axis=1), z[mask][finite], rtol=1e-4, atol=1e-5)
        cosine = np.sum(seen[finite] * bearings[mask][finite], axis=1) / np.linalg.norm(seen[finite], axis=1)
        assert np.median(np.degrees(np.arccos(np.clip(cosine, -1, 1)))) < 0.5


def test_export_refuses_a_capture_without_truth(dataset, tmp_path):
    manifest = json.loads(dataset.read_text())
    for frame in manifest["frames"]:
        for view in frame["views"]:
            view.pop("ground_truth", None)
            view["image"] = str((dataset.parent / view["image"]).resolve().relative_to(dataset.parent.resolve()))
    bare = dataset.parent / "capture.json"
    bare.write_text(json.dumps(manifest))
    import subprocess
    from conftest import BINARY

    p = subprocess.run([str(BINARY), "export", "--dataset", str(bare), "--out", str(tmp_path / "e")],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "has no ground truth" in p.stderr, p.stderr
    assert not (tmp_path / "e").exists()
    bare.unlink()
