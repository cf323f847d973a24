"""OpenCV's fisheye model from Python: every file form loads, points match cv2.fisheye, rays
reach past 90°, and the warp rectifies like cv2.fisheye.initUndistortRectifyMap."""

import json
import os

import cv2
import numpy as np
import pytest

import vklens

from conftest import SHARED

FISH = str(SHARED / "reference" / "fisheye")
INDEX = json.load(open(os.path.join(FISH, "index.json")))["cameras"]


def k_d(c):
    return (np.array([[c["fx"], 0, c["cx"]], [0, c["fy"], c["cy"]], [0, 0, 1.0]]),
            np.array(c["dist_coeffs"], dtype=np.float64))


@pytest.mark.parametrize("c", INDEX, ids=[c["name"] for c in INDEX])
def test_every_form_loads_the_same_fisheye(c):
    cams = [vklens.Camera.load(os.path.join(FISH, f["path"])) for f in c["files"]]
    for cam in cams:
        assert cam.model == "opencv_fisheye"
        np.testing.assert_allclose(cam.dist_coeffs, c["dist_coeffs"], atol=0)
        np.testing.assert_allclose([cam.fx, cam.fy, cam.cx, cam.cy], [c["fx"], c["fy"], c["cx"], c["cy"]], atol=1e-12)
    # The skew is K[0][1] = α fx.
    assert cams[0].K[0, 1] == pytest.approx(c["alpha"] * c["fx"], abs=1e-12)
    assert "opencv_fisheye" in repr(cams[0])
    # Pickling (Ray, multiprocessing) keeps the model.
    import pickle
    assert pickle.loads(pickle.dumps(cams[0])) == cams[0]


@pytest.mark.parametrize("c", INDEX, ids=[c["name"] for c in INDEX])
def test_points_match_cv2_fisheye_and_rays_reach_past_90_degrees(c):
    cam = vklens.Camera.load(os.path.join(FISH, f"{c['name']}.json"))
    pts = json.load(open(os.path.join(FISH, c["points"])))
    xyz = np.array(pts["inside"]["xyz"])
    K, D = k_d(c)
    theirs, _ = cv2.fisheye.projectPoints(xyz.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, D, alpha=c["alpha"])
    np.testing.assert_allclose(cam.project_points(xyz), theirs.reshape(-1, 2), atol=1e-9)
    beyond = pts["beyond90"]
    if beyond["xyz"]:
        np.testing.assert_allclose(cam.project_points(np.array(beyond["xyz"])), np.array(beyond["pixel"]), atol=1e-9)
        rays = cam.unproject_points(np.array(beyond["pixel"]))
        truth = np.array(beyond["xyz"]) / np.linalg.norm(beyond["xyz"], axis=1, keepdims=True)
        np.testing.assert_allclose(rays, truth, atol=1e-9)
        assert (rays[:, 2] <= 1e-12).all()
        # Normalized (x, y) cannot hold them: NaN.
        assert np.isnan(cam.undistort_points(np.array(beyond["pixel"]))).all()
    # The standard model's inverses are not the fisheye's.
    with pytest.raises(vklens.InputError, match="newton"):
        cam.undistort_points([[10.0, 10.0]], method="heikkila")


def test_the_warp_rectifies_a_fisheye_like_cv2():
    c = next(c for c in INDEX if c["name"] == "fish_wide160")
    cam = vklens.Camera.load(os.path.join(FISH, "fish_wide160.json"))
    h, w = c["height"], c["width"]
    y, x = np.mgrid[0:h, 0:w]
    photo = np.dstack([128 + 100 * np.sin(x / 9.0), 128 + 100 * np.cos(y / 11.0), 128 + 90 * np.sin((x + y) / 13.0)]).astype(np.uint8)
    warper = vklens.Warper(cam, direction="undistort")
    ours, mask = warper(photo, return_mask=True)
    K, D = k_d(c)
    mx, my = cv2.fisheye.initUndistortRectifyMap(K, D, np.eye(3), K, (w, h), cv2.CV_32FC1)
    theirs = cv2.remap(photo, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    inner = mask & (mx >= 0.5) & (my >= 0.5) & (mx <= w - 1.5) & (my <= h - 1.5)
    d = np.abs(ours.astype(int) - theirs.astype(int))[inner]
    assert inner.sum() > 1_000_000 and d.max() <= 1 and d.mean() < 0.05
