"""hovs.Unwrapper against `hovs unwrap` on the same model and image, against cv2.remap with the same maps, and
its mapping files."""

import cv2
import numpy as np
import pytest

import hovs

from conftest import run_hovs


@pytest.fixture(scope="module")
def model_and_image(dataset, calibration):
    data = hovs.Dataset(str(dataset))
    image = data.image(data.frames[0])
    return str(calibration / "calibration.json"), image


def test_views_are_the_clis_views(model_and_image, tmp_path):
    model, image = model_and_image
    path = tmp_path / "frame.png"
    cv2.imwrite(str(path), cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
    run_hovs("unwrap", "--model", model, "--layout", "article", "--input", path, "--out", tmp_path / "out")
    u = hovs.Unwrapper(hovs.load_camera(model), "article")
    assert len(u.views) == 6 and all(v["type"] == "perspective" for v in u.views)
    views = u.remap(image)
    assert len(views) == 6
    for spec, view in zip(u.views, views):
        cli = cv2.cvtColor(cv2.imread(str(tmp_path / "out" / "frame" / f"{spec['name']}.png")), cv2.COLOR_BGR2RGB)
        assert view.shape == (spec["height"], spec["width"], 3)
        assert np.array_equal(view, cli), spec["name"]


def test_maps_drive_cv2_remap(model_and_image):
    model, image = model_and_image
    u = hovs.Unwrapper(hovs.load_camera(model), "panorama")
    (view,) = u.remap(image)
    map_x, map_y = u.maps(0)
    assert map_x.dtype == np.float32 and map_x.shape == view.shape[:2]
    ref = cv2.remap(image, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    inside = (map_x >= 1) & (map_y >= 1) & (map_x < image.shape[1] - 2) & (map_y < image.shape[0] - 2)
    assert inside.mean() > 0.9
    diff = np.abs(ref.astype(int) - view.astype(int))[inside]
    assert diff.mean() < 1.0 and np.percentile(diff, 99) <= 3


def test_saved_mapping_file_gives_the_same_views(model_and_image, tmp_path):
    model, image = model_and_image
    u = hovs.Unwrapper(hovs.load_camera(model), "article", interpolation="bicubic")
    u.save(str(tmp_path / "views.hmap"))
    v = hovs.Unwrapper.load(str(tmp_path / "views.hmap"), interpolation="bicubic")
    assert v.source_size == (image.shape[1], image.shape[0])
    for a, b in zip(u.remap(image), v.remap(image)):
        assert np.array_equal(a, b)


def test_grey_and_bayer_frames(model_and_image):
    model, image = model_and_image
    u = hovs.Unwrapper(hovs.load_camera(model), "article")
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    (g0, *_) = u.remap(grey)
    assert g0.ndim == 2
    # An RGGB mosaic of a smooth frame (where demosaicing loses nothing visible) gives the RGB frame's views.
    v, u_ = np.mgrid[0 : image.shape[0], 0 : image.shape[1]].astype(float)
    image = np.stack([128 + 100 * np.sin(u_ / 40), 128 + 100 * np.cos(v / 35), 128 + 60 * np.sin((u_ + v) / 50)], -1)
    image = np.round(image).astype(np.uint8)
    bayer = np.zeros(image.shape[:2], np.uint8)
    bayer[0::2, 0::2] = image[0::2, 0::2, 0]
    bayer[0::2, 1::2] = image[0::2, 1::2, 1]
    bayer[1::2, 0::2] = image[1::2, 0::2, 1]
    bayer[1::2, 1::2] = image[1::2, 1::2, 2]
    rgb_views, bayer_views = u.remap(image), u.remap(bayer, format="bayer_rggb")
    for a, b in zip(rgb_views, bayer_views):
        assert b.shape == a.shape
        diff = np.abs(a.astype(int) - b.astype(int))
        assert diff.mean() < 1.0 and np.percentile(diff, 99) <= 4


def test_bad_frames_are_refused(model_and_image):
    model, image = model_and_image
    u = hovs.Unwrapper(hovs.load_camera(model), "article")
    with pytest.raises(hovs.Error, match="image.*550 x 440"):
        u.remap(image[:100])
    with pytest.raises(TypeError, match="image: expected a uint8 image"):
        u.remap(image.astype(np.float32))
    with pytest.raises(hovs.Error, match="image.*shape"):
        u.remap(image[:, :, :2])
    with pytest.raises(hovs.Error, match="view.*no view named 'nope'"):
        u.maps("nope")
    with pytest.raises(hovs.Error, match="bayer_rggb needs 1 channel"):
        u.remap(image, format="bayer_rggb")
