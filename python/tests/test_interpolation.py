"""The warp's interpolation and border choices against cv2.remap run on the warper's own maps:
the same source positions, so only the sampling is compared."""

import cv2
import numpy as np
import pytest

import vklens
from conftest import camera_of, smooth_image

INTER = {"nearest": cv2.INTER_NEAREST, "bilinear": cv2.INTER_LINEAR, "bicubic": cv2.INTER_CUBIC}
BORDER = {"constant": cv2.BORDER_CONSTANT, "replicate": cv2.BORDER_REPLICATE,
          "reflect": cv2.BORDER_REFLECT}


@pytest.fixture(scope="module")
def barrel(reference):
    # Barrel distortion: the lens image's corners see past the pinhole source's frame, where
    # the borders differ.
    return camera_of(reference["seed_fig2"])


@pytest.mark.parametrize("border", list(BORDER))
@pytest.mark.parametrize("interpolation", list(INTER))
def test_sampling_equals_cv2_remap(barrel, device, interpolation, border):
    w, h = barrel.size
    image = smooth_image(w, h, channels=3, dtype=np.float32)
    warper = vklens.Warper(barrel, direction="distort", interpolation=interpolation,
                           border=border, device=device)
    assert (warper.interpolation, warper.border) == (interpolation, border)
    ours, mask = warper(image, return_mask=True)
    mx, my = warper.maps()
    theirs = cv2.remap(image, mx, my, INTER[interpolation], borderMode=BORDER[border])
    off_frame = (mx < -0.5) | (my < -0.5) | (mx > w - 0.5) | (my > h - 0.5)
    assert off_frame.sum() > w * h // 100, "the test needs positions off the source frame"
    if border == "constant":
        # vklens fills a pixel whose position is off the frame; OpenCV blends the border value
        # into taps past the edge, so the two differ only within two pixels of the frame.
        assert not mask[off_frame].any() and (ours[off_frame] == 0).all()
        near_edge = (mx < 1.5) | (my < 1.5) | (mx > w - 2.5) | (my > h - 2.5)
        compared = ~near_edge
    else:
        assert mask.all()
        compared = np.ones_like(mask)
    diff = np.abs(ours - theirs)[compared]
    if interpolation == "nearest":
        # Rounding ties (f32 positions within 1e-3 px of a half-pixel) may pick the other
        # neighbour: one pixel in thousands at most.
        assert (diff > 1e-6).mean() < 1e-3
    else:
        # OpenCV quantizes positions to 1/32 px; on these sinusoids that moves a value by at
        # most ~0.004 (a grey level is 0.0039).
        assert diff.mean() < 2e-4 and diff.max() < 6e-3, (diff.mean(), diff.max())


def test_bicubic_is_sharper_than_bilinear_and_overshoots_as_opencv(device):
    # A hard vertical edge, shifted by half a pixel: bilinear gives the midpoint, bicubic
    # OpenCV's overshoot on either side (float images keep it).
    cam = vklens.Camera(width=64, height=32, fx=60, fy=60, cx=31.5, cy=15.5)
    image = np.zeros((32, 64), np.float32)
    image[:, 32:] = 1.0
    src = vklens.Camera(width=64, height=32, fx=60, fy=60, cx=32.0, cy=15.5)
    out = {i: vklens.Warper(cam, direction="undistort", source_camera=src, method="newton",
                            interpolation=i, device=device)(image)
           for i in ("bilinear", "bicubic")}
    mx, my = vklens.Warper(cam, direction="undistort", source_camera=src, method="newton",
                           device=device).maps()
    cubic = cv2.remap(image, mx, my, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)
    row = 16
    assert out["bicubic"].min() < -0.05 and out["bicubic"].max() > 1.05
    assert np.abs(out["bicubic"][row, 2:-2] - cubic[row, 2:-2]).max() < 1e-3
    assert out["bilinear"].min() >= 0.0 and out["bilinear"].max() <= 1.0


def test_uint8_bicubic_clamps_as_opencv(barrel, device):
    w, h = barrel.size
    image = smooth_image(w, h, channels=4, dtype=np.uint8)
    warper = vklens.Warper(barrel, direction="distort", interpolation="bicubic",
                           border="reflect", device=device)
    mx, my = warper.maps()
    theirs = cv2.remap(image, mx, my, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    diff = np.abs(warper(image).astype(int) - theirs.astype(int))
    assert diff.max() <= 1 and diff.mean() < 0.05


@pytest.mark.parametrize("kwargs, word", [({"interpolation": "lanczos"}, "interpolation"),
                                          ({"border": "wrap"}, "border")])
def test_unknown_choices_are_refused_by_name(barrel, device, kwargs, word):
    with pytest.raises(vklens.InputError, match=word):
        vklens.Warper(barrel, device=device, **kwargs)
