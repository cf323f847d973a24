"""Rectification as OpenCV and ROS image_proc do it: a stereo pair's R and P (from
cv2.stereoRectify and cv2.fisheye.stereoRectify) in the warp and in undistort_points, against
cv2.initUndistortRectifyMap / cv2.undistortPoints themselves."""

import json
import os

import cv2
import numpy as np
import pytest

import vklens

from conftest import SHARED, camera_of, k_d

SIZE = (640, 480)
STEREO_R, _ = cv2.Rodrigues(np.array([0.01, -0.03, 0.005]))
STEREO_T = np.array([[-0.12], [0.002], [0.001]])
TIGHT = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)


def standard_pair(reference):
    """Two cameras of the shared reference (webcam_plumb_bob, and seed_fig2 scaled to its size)
    rectified as a pair."""
    a = reference["webcam_plumb_bob"]
    K1, D1 = k_d(a)
    K2 = K1 * np.array([[1.01, 1, 1], [1, 1.005, 1], [1, 1, 1]]) + np.array([[0, 0, 2.5], [0, 0, -1.5], [0, 0, 0]])
    D2 = D1 * 0.95
    size = (a["width"], a["height"])
    R1, R2, P1, P2 = cv2.stereoRectify(K1, D1, K2, D2, size, STEREO_R, STEREO_T, alpha=0)[:4]
    cams = [vklens.Camera.from_opencv(K1, D1, size), vklens.Camera.from_opencv(K2, D2, size)]
    return cams, [(K1, D1, R1, P1), (K2, D2, R2, P2)], size


def fisheye_pair():
    c = json.load(open(os.path.join(SHARED / "reference" / "fisheye", "fish_wide160.json")))
    K1, D1 = (np.array([[c["fx"], 0, c["cx"]], [0, c["fy"], c["cy"]], [0, 0, 1.0]]),
              np.array(c["dist_coeffs"], dtype=np.float64))
    K2 = K1 * np.array([[0.995, 1, 1], [1, 1.0, 1], [1, 1, 1]])
    D2 = D1 * 1.02
    size = (c["width"], c["height"])
    R1, R2, P1, P2 = cv2.fisheye.stereoRectify(K1, D1, K2, D2, size, STEREO_R, STEREO_T,
                                               flags=cv2.CALIB_ZERO_DISPARITY, balance=0.0)[:4]

    def fisheye(K, D):
        return vklens.Camera(width=size[0], height=size[1], fx=K[0, 0], fy=K[1, 1], cx=K[0, 2],
                             cy=K[1, 2], model="opencv_fisheye", dist_coeffs=list(D))

    return [fisheye(K1, D1), fisheye(K2, D2)], [(K1, D1, R1, P1), (K2, D2, R2, P2)], size


@pytest.mark.parametrize("model", ["standard", "fisheye"])
def test_warper_maps_equal_init_undistort_rectify_map(reference, device, model):
    cams, mats, size = standard_pair(reference) if model == "standard" else fisheye_pair()
    maps = cv2.initUndistortRectifyMap if model == "standard" else cv2.fisheye.initUndistortRectifyMap
    for cam, (K, D, R, P) in zip(cams, mats):
        map_x, map_y = vklens.Warper(cam, direction="undistort", R=R, P=P, device=device).maps()
        mx, my = maps(K, D, R, P, size, cv2.CV_32FC1)
        valid = ~np.isnan(map_x)
        assert valid.mean() > 0.9, "the rectified view is mostly inside the lens's valid domain"
        assert np.abs(map_x - mx)[valid].max() <= 1e-3 and np.abs(map_y - my)[valid].max() <= 1e-3
        # The 3×4 projection matrix gives the same warp as its 3×3 part.
        map_x4, _ = vklens.Warper(cam, direction="undistort", R=R, P=np.asarray(P)[:, :3],
                                  device=device).maps()
        np.testing.assert_array_equal(map_x, map_x4)


def test_rectified_image_equals_opencv_remap(reference, device):
    cams, mats, size = standard_pair(reference)
    w, h = size
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    photo = np.clip(np.dstack([128 + 100 * np.sin(x / 9) * np.cos(y / 11),
                               128 + 100 * np.sin((x + y) / 13),
                               128 + 100 * np.cos(x / 7 - y / 17)]), 0, 255).round().astype(np.uint8)
    for cam, (K, D, R, P) in zip(cams, mats):
        ours, mask = vklens.Warper(cam, direction="undistort", R=R, P=P, device=device)(photo, return_mask=True)
        mx, my = cv2.initUndistortRectifyMap(K, D, R, P, size, cv2.CV_32FC1)
        theirs = cv2.remap(photo, mx, my, cv2.INTER_LINEAR)
        inner = mask & (mx >= 0.5) & (my >= 0.5) & (mx <= w - 1.5) & (my <= h - 1.5)
        d = np.abs(ours.astype(int) - theirs.astype(int))[inner]
        assert inner.mean() > 0.9 and d.mean() <= 0.05 and d.max() <= 1
        plain = vklens.Warper(cam, direction="undistort", device=device)(photo)
        assert np.abs(plain.astype(int) - theirs.astype(int))[inner].mean() > 5, "R and P change the image"


@pytest.mark.parametrize("model", ["standard", "fisheye"])
def test_undistort_points_with_r_and_p_equal_opencv(reference, model):
    cams, mats, size = standard_pair(reference) if model == "standard" else fisheye_pair()
    rng = np.random.default_rng(3)
    for cam, (K, D, R, P) in zip(cams, mats):
        uv = rng.uniform([40, 40], [size[0] - 40, size[1] - 40], (300, 2))
        for r, p in [(R, P), (R, None), (None, P)]:
            ours = cam.undistort_points(uv, R=r, P=p)
            if model == "standard":
                theirs = cv2.undistortPoints(uv.reshape(-1, 1, 2), K, D, R=r, P=p, criteria=TIGHT).reshape(-1, 2)
            else:
                theirs = cv2.fisheye.undistortPoints(uv.reshape(-1, 1, 2), K, D, R=r, P=p,
                                                     criteria=TIGHT).reshape(-1, 2)
            # NaN exactly where the lens sees no such point (outside a fisheye's valid circle)
            # or the ray lies at or behind the (turned) image plane; OpenCV returns numbers
            # there.
            rays = cam.unproject_points(uv)
            turned = rays @ (np.eye(3) if r is None else np.asarray(r)).T
            nowhere = np.isnan(rays).any(axis=1) | (rays[:, 2] <= 0) | (turned[:, 2] <= 0)
            valid = ~np.isnan(ours).any(axis=1)
            np.testing.assert_array_equal(valid, ~nowhere)
            assert valid.mean() > 0.8
            compared = valid
            if model == "fisheye":
                # cv2.fisheye.undistortPoints clamps the distorted angle θd to 90°, so past it
                # OpenCV answers another point; vklens's rays reproject through
                # cv2.fisheye.projectPoints onto the pixels they came from.
                theta_d = np.hypot((uv[:, 0] - K[0, 2]) / K[0, 0], (uv[:, 1] - K[1, 2]) / K[1, 1])
                compared = valid & (theta_d < np.pi / 2)
                back, _ = cv2.fisheye.projectPoints(rays[valid].reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, D)
                assert np.abs(back.reshape(-1, 2) - uv[valid]).max() <= 1e-6
            scale = 1.0 if p is not None else K[0, 0]  # in pixels either way
            assert compared.mean() > 0.8
            assert np.abs(ours - theirs)[compared].max() * scale <= 1e-6
    # R = I without P: the normalized coordinates of the plain call (through the unit ray: to
    # rounding).
    plain = cams[0].undistort_points(uv)
    known = ~np.isnan(plain).any(axis=1)
    np.testing.assert_allclose(cams[0].undistort_points(uv, R=np.eye(3))[known], plain[known],
                               rtol=0, atol=1e-14)


def test_bad_r_and_p_raise_input_error_naming_them(reference, device):
    cam = camera_of(reference["webcam_plumb_bob"])
    with pytest.raises(vklens.InputError, match="R"):
        vklens.Warper(cam, direction="distort", R=np.eye(3), device=device)
    with pytest.raises(vklens.InputError, match="P"):
        vklens.Warper(cam, direction="undistort", P=cam.K, source_camera=cam, device=device)
    with pytest.raises(vklens.InputError, match="P"):
        vklens.Warper(cam, direction="undistort", P=np.eye(4), device=device)
    with pytest.raises(vklens.InputError, match="rotation"):
        vklens.Warper(cam, direction="undistort", R=np.diag([1.0, 1.0, -1.0]), device=device)
    with pytest.raises(vklens.InputError, match="R"):
        cam.undistort_points(np.zeros((1, 2)), R=np.full((3, 3), np.nan))
