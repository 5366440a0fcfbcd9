"""hovs.Dataset against the files the CLI wrote: images as OpenCV reads them, ground-truth EXR channels, the
manifest."""

import json

import cv2
import numpy as np
import pytest

import hovs


def test_images_and_manifest(dataset):
    data = hovs.Dataset(str(dataset))
    manifest = json.loads(dataset.read_text())
    assert data.manifest == manifest
    assert data.units == [u["name"] for u in manifest["units"]]
    assert data.frames == [f["id"] for f in manifest["frames"]]
    for frame in manifest["frames"]:
        view = frame["views"][0]
        image = data.image(frame["id"])
        ref = cv2.cvtColor(cv2.imread(str(dataset.parent / view["image"])), cv2.COLOR_BGR2RGB)
        assert image.dtype == np.uint8 and np.array_equal(image, ref)
        f = data.image(frame["id"], as_float=True)
        assert f.dtype == np.float32 and np.abs(f * 255 - image).max() <= 0.5 + 1e-3


def test_ground_truth_channels(dataset):
    data = hovs.Dataset(str(dataset))
    truth = data.ground_truth(data.frames[0], data.units[0])
    assert len(truth) >= 3
    for name, channel in truth.items():
        assert channel.shape == (440, 550) and channel.dtype == np.float32, name
    # Every pixel that sees the board has a finite value in every channel.
    assert all(np.isfinite(c).mean() > 0.5 for c in truth.values())


def test_missing_frame_and_unit(dataset):
    data = hovs.Dataset(str(dataset))
    with pytest.raises(hovs.Error, match="dataset.json: no frame 999"):
        data.image(999)
    with pytest.raises(hovs.Error, match="has no view of unit 'left'"):
        data.corners(data.frames[0], "left")


def test_not_a_manifest(tmp_path):
    bad = tmp_path / "dataset.json"
    bad.write_text('{"format": "something-else"}')
    with pytest.raises(hovs.Error, match=str(bad)):
        hovs.Dataset(str(bad))
