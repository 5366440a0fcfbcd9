"""hovs.calibrate on the dataset's exact corners against `hovs calibrate --truth-corners` on the same dataset."""

import json

import numpy as np
import pytest

import hovs


def test_calibration_from_arrays_is_the_clis(dataset, calibration):
    data = hovs.Dataset(str(dataset))
    observations = []
    for frame in data.frames:
        c = data.corners(frame)
        observations.append({"board_xy": c["board_xy"], "pixels": c["pixels"], "image": f"frame{frame}"})
    record, poly, unified = hovs.calibrate(observations, 550, 440)
    cli = json.loads((calibration / "calibration.json").read_text())
    assert record["polynomial"]["rms_px"] == pytest.approx(cli["polynomial"]["rms_px"], rel=1e-6, abs=1e-9)
    assert record["unified"]["rms_px"] == pytest.approx(cli["unified"]["rms_px"], rel=1e-6, abs=1e-9)
    assert len(record["polynomial"]["board_poses"]) == len(observations)
    cli_poly = hovs.load_camera(str(calibration / "calibration.json"), model="polynomial")
    grid = np.stack(np.meshgrid(np.arange(0, 550, 10.0), np.arange(0, 440, 10.0)), -1).reshape(-1, 2)
    a, va = poly.unproject(grid)
    b, vb = cli_poly.unproject(grid)
    both = va & vb
    assert both.sum() > 500
    assert np.linalg.norm(a[both] - b[both], axis=1).max() < 1e-9  # radians: the same model to rounding
    # The exact corners calibrate both models to well under a hundredth of a pixel.
    assert record["polynomial"]["rms_px"] < 0.01 and unified.kind == "unified"


def test_bad_observations():
    good = {"board_xy": np.zeros((6, 2)), "pixels": np.zeros((6, 2))}
    with pytest.raises(hovs.Error, match=r"observations\[1\].*same number of rows"):
        hovs.calibrate([good, {"board_xy": np.zeros((6, 2)), "pixels": np.zeros((5, 2))}], 640, 480)
    with pytest.raises(TypeError, match=r"observations\[0\]: expected a dict"):
        hovs.calibrate([np.zeros((6, 2))], 640, 480)
    with pytest.raises(hovs.Error, match="degree"):
        hovs.calibrate([good], 640, 480, degree=12)
