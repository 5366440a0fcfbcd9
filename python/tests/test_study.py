"""Design metrics against the article's reference system and `hovs design`; stereo triangulation against points
known exactly."""

import json
import math

import numpy as np
import pytest

import hovs

from conftest import run_hovs


def test_reference_mirror_metrics(source_dir):
    config = str(source_dir / "design" / "reference.yaml")
    m = hovs.design_metrics(config, 0.048, 0.044)
    assert m["c"] == pytest.approx(math.hypot(0.048, 0.044), abs=1e-12)
    assert m["vertical_field_deg"] == pytest.approx(m["upper_bound_deg"] - m["lower_bound_deg"])
    assert m["constraints"] and all({"name", "value", "limit", "satisfied"} <= c.keys() for c in m["constraints"])
    res = hovs.radial_resolution(config, 0.048, 0.044, n=50)
    assert res.shape == (50, 3)
    assert np.all(np.diff(res[:, 0]) > 0) and np.all(res[:, 2] > 0)


def test_study_and_metrics_match_the_design_report(source_dir, tmp_path):
    config = source_dir / "design" / "reference.yaml"
    run_hovs("design", "--config", config, "--out", tmp_path / "design", display=True)
    report = json.loads((tmp_path / "design" / "design.json").read_text())
    study = hovs.design_study(str(config))
    for key in ("continuous_optimum", "integer_mm_optimum", "marked_design"):
        assert (study[key] is None) == (report[key] is None), key
    best = report["continuous_optimum"]
    assert study["continuous_optimum"]["a"] == pytest.approx(best["a"], abs=1e-12)
    assert study["continuous_optimum"]["b"] == pytest.approx(best["b"], abs=1e-12)
    m = hovs.design_metrics(str(config), best["a"], best["b"], best["d"])
    for key in ("c", "upper_bound_deg", "lower_bound_deg", "rim_radius_px", "system_length"):
        assert m[key] == pytest.approx(best[key], rel=1e-12, abs=1e-12), key
    assert [c["name"] for c in m["constraints"]] == [c["name"] for c in best["constraints"]]


def test_triangulation_recovers_known_points():
    rng = np.random.default_rng(5)
    angle = math.radians(3.0)
    R = np.array([[math.cos(angle), -math.sin(angle), 0], [math.sin(angle), math.cos(angle), 0], [0, 0, 1]])
    t = np.array([-0.4, 0.02, 0.01])
    right_from_left = np.eye(4)
    right_from_left[:3, :3], right_from_left[:3, 3] = R, t
    points = rng.uniform([-10, -10, -2], [10, 10, 1], size=(500, 3))
    left = points / np.linalg.norm(points, axis=1, keepdims=True)
    in_right = points @ R.T + t
    right = in_right / np.linalg.norm(in_right, axis=1, keepdims=True)
    out = hovs.triangulate(left, right, right_from_left, sigma_deg=0.01)
    ok = out["valid"]
    assert ok.mean() > 0.95
    assert np.abs(out["points"][ok] - points[ok]).max() < 1e-6
    assert np.allclose(out["range"][ok], np.linalg.norm(points[ok], axis=1))
    assert np.all(out["sigma_range"][ok] > 0) and np.all(out["gap"][ok] < 1e-9)
    with pytest.raises(hovs.Error, match="right_from_left.*not a rigid transform"):
        hovs.triangulate(left, right, np.ones((4, 4)))


def test_open3d_reads_the_point_clouds(tmp_path):
    """Open3D reads hovs' PLY (the writer of `hovs depth`) with every coordinate and colour intact."""
    import open3d  # scripts/setup.sh installs python3-open3d

    rng = np.random.default_rng(2)
    points = rng.uniform(-30, 30, size=(1000, 3))
    colors = rng.integers(0, 256, size=(1000, 3), dtype=np.uint8)
    hovs.write_point_cloud(str(tmp_path / "points.ply"), points, colors)
    cloud = open3d.io.read_point_cloud(str(tmp_path / "points.ply"))
    # The writer stores float32 with 9 digits: read back and rounded to float32, every coordinate is the same.
    assert np.array_equal(np.asarray(cloud.points).astype(np.float32), points.astype(np.float32))
    assert np.array_equal(np.round(np.asarray(cloud.colors) * 255).astype(np.uint8), colors)
    with pytest.raises(hovs.Error, match="colors.*has 2 rows"):
        hovs.write_point_cloud(str(tmp_path / "bad.ply"), points, colors[:2])
