"""`hovs unwrap --colmap` read by a reader written from COLMAP's documentation of its text format: a board corner
projected through COLMAP's camera and pose lands, in hovs' view, on the view pixel whose source is the corner's
exact pixel in the frame."""

import numpy as np

import hovs

from conftest import run_hovs


def read_colmap(folder):
    """cameras.txt and images.txt: comment lines start with '#'; an image is two lines (pose, 2-D points)."""
    cameras = {}
    for line in (folder / "cameras.txt").read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        f = line.split()
        cameras[int(f[0])] = {"model": f[1], "width": int(f[2]), "height": int(f[3]),
                              "params": np.array([float(x) for x in f[4:]])}
    lines = [line for line in (folder / "images.txt").read_text().splitlines() if not line.startswith("#")]
    images = []
    for pose, _points in zip(lines[0::2], lines[1::2]):
        f = pose.split()
        qw, qx, qy, qz = map(float, f[1:5])
        R = np.array([[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
                      [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
                      [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]])
        images.append({"id": int(f[0]), "R": R, "t": np.array([float(x) for x in f[5:8]]), "camera": int(f[8]),
                       "name": f[9]})
    return cameras, images


def bilinear(image, u, v):
    u0, v0 = int(np.floor(u)), int(np.floor(v))
    a, b = u - u0, v - v0
    patch = image[v0 : v0 + 2, u0 : u0 + 2]
    return (1 - a) * (1 - b) * patch[0, 0] + a * (1 - b) * patch[0, 1] + (1 - a) * b * patch[1, 0] + a * b * patch[1, 1]


def test_colmap_cameras_and_poses_match_the_views(dataset, tmp_path):
    out = tmp_path / "views"
    run_hovs("unwrap", "--model", dataset, "--input", dataset, "--layout", "article", "--colmap", "--out", out)
    cameras, images = read_colmap(out / "colmap")
    data = hovs.Dataset(str(dataset))
    views = hovs.Unwrapper(data.camera(), "article")
    assert len(cameras) == 6 and all(c["model"] == "PINHOLE" for c in cameras.values())
    assert len(images) == 6 * len(data.frames)
    assert (out / "colmap" / "points3D.txt").exists()
    names = [v["name"] for v in views.views]
    maps = {name: views.maps(name) for name in names}
    checked, worst = 0, 0.0
    for image in images:
        frame_name, view_file = image["name"].split("/")
        assert (out / image["name"]).exists()
        frame = int(frame_name.removeprefix("frame"))
        corners = data.corners(frame)
        cam = cameras[image["camera"]]
        fx, fy, cx, cy = cam["params"]
        xc = corners["world"] @ image["R"].T + image["t"]
        map_x, map_y = maps[view_file.removesuffix(".png")]
        for X, exact in zip(xc, corners["pixels"]):
            if X[2] <= 0:
                continue
            # COLMAP's pixel centres are at half integers; hovs' at integers.
            u, v = fx * X[0] / X[2] + cx - 0.5, fy * X[1] / X[2] + cy - 0.5
            if not (1 <= u < cam["width"] - 2 and 1 <= v < cam["height"] - 2):
                continue
            source = np.array([bilinear(map_x, u, v), bilinear(map_y, u, v)])
            if (source < 0).any():
                continue
            worst = max(worst, np.linalg.norm(source - exact))
            checked += 1
    print(f"{checked} corners through COLMAP's cameras, worst {worst:.4f} px")
    assert checked > 50 and worst < 0.05


def test_colmap_needs_a_perspective_view(dataset, tmp_path):
    import subprocess
    from conftest import BINARY

    p = subprocess.run([str(BINARY), "unwrap", "--model", str(dataset), "--input", str(dataset), "--layout",
                        "panorama", "--colmap", "--out", str(tmp_path / "o")], capture_output=True, text=True)
    assert p.returncode == 2 and "no perspective view" in p.stderr
    assert not (tmp_path / "o").exists()
