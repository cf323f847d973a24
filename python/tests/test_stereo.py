"""vklens.stereo_rectify against OpenCV itself: cv2.stereoRectify for the standard model,
cv2.fisheye.stereoRectify for the fisheye, on horizontal and vertical pairs, every option; the
rectified images of `vklens stereo-rectify --left --right` against cv2.initUndistortRectifyMap +
cv2.remap."""

import json
import subprocess

import cv2
import numpy as np
import pytest

import vklens

from conftest import SHARED, k_d, smooth_image

# OpenCV's undistortPoints until it has converged (its default stops after 5 iterations).
CONVERGED = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)


def k_of(fx, fy, cx, cy):
    return np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])


# Standard-model pairs on which OpenCV's 5 iterations have converged at the corners and the
# grid (checked below): plumb bob, and rational with thin prism and tilt.
MILD = {
    "plumb_bob": (k_of(600, 610, 330.2, 236.9), np.array([-0.05, 0.01, 0.001, -0.0015, 0.0]),
                  k_of(605, 603, 322.2, 240.1), np.array([-0.06, 0.012, -0.0005, 0.001, 0.0]),
                  (640, 480)),
    "rational_prism_tilt": (
        k_of(800, 790, 515.3, 380.2),
        np.array([-0.12, 0.04, 0.002, -0.001, 0, 0.01, 0.002, 0, 0.003, -0.0005, -0.002, 0.0004,
                  0.01, -0.015]),
        k_of(803, 795, 509.1, 388.9),
        np.array([-0.11, 0.035, 0.0015, -0.0012, 0, 0.012, 0.001, 0, 0.002, -0.0004, -0.001,
                  0.0003, -0.008, 0.012]),
        (1024, 768)),
}

# X2 = R X1 + T: the second camera 12 cm to the right, or 10 cm below (|T_y| > |T_x|).
PAIRS = {
    "horizontal": (np.array([0.01, -0.02, 0.005]), np.array([-0.12, 0.003, 0.001])),
    "vertical": (np.array([0.01, 0.02, -0.01]), np.array([0.002, -0.1, 0.004])),
}


def rotation(rvec):
    return cv2.Rodrigues(np.asarray(rvec, np.float64).reshape(3, 1))[0]


def flags_of(zero_disparity):
    return cv2.CALIB_ZERO_DISPARITY if zero_disparity else 0


def outputs(s):
    """What cv2.stereoRectify returns, from a vklens.StereoRectification or such a tuple."""
    if isinstance(s, vklens.StereoRectification):
        return s.R1, s.R2, s.P1, s.P2, s.Q, s.roi1, s.roi2
    return tuple(s)


def assert_matches(ours, theirs, rtol):
    """Every output of cv2.stereoRectify: R1 R2 to rounding (measured: 8.5e-15, OpenCV's
    products summed in another order), P1 P2 Q to `rtol` of their largest entry, the ROIs
    (where `theirs` has them) exactly."""
    ours, theirs = outputs(ours), outputs(theirs)
    for got, want in zip(ours[:2], theirs[:2]):
        np.testing.assert_allclose(got, want, rtol=0, atol=5e-14)
    for got, want in zip(ours[2:5], theirs[2:5]):
        np.testing.assert_allclose(got, want, rtol=0, atol=rtol * np.abs(want).max())
    if len(theirs) > 5:
        assert tuple(ours[5]) == tuple(theirs[5]) and tuple(ours[6]) == tuple(theirs[6])


def opencv_rule(K1, D1, K2, D2, size, R, T, alpha=None, new_size=None, zero_disparity=True,
                criteria=None):
    """cv2.stereoRectify's rule written on cv2.undistortPoints with the given criteria (None:
    OpenCV's default, 5 iterations), returning what cv2.stereoRectify returns: checked below to
    be OpenCV's own, to rounding, with its default criteria."""
    w, h = size
    nw, nh = new_size or size
    r_r = rotation(-0.5 * cv2.Rodrigues(R)[0])
    t = r_r @ T
    idx = 0 if abs(t[0]) > abs(t[1]) else 1
    axis = np.zeros(3)
    axis[idx] = 1.0 if t[idx] > 0 else -1.0
    ww = np.cross(t, axis)
    ww *= np.arccos(abs(t[idx]) / np.linalg.norm(t)) / np.linalg.norm(ww)
    wR = rotation(ww)
    R1, R2 = wR @ r_r.T, wR @ r_r
    t_idx = (R2 @ T)[idx]
    args = {} if criteria is None else {"criteria": criteria}
    ratio = nw / w / 2 if idx == 1 else nh / h / 2
    fc = (K1[idx ^ 1, idx ^ 1] + K2[idx ^ 1, idx ^ 1]) * ratio
    cameras = [(K1, D1, R1), (K2, D2, R2)]
    c0 = []
    for K, D, Rk in cameras:
        # OpenCV holds the corners as float32 through undistortPoints and projectPoints.
        corners = np.array([[0, 0], [w - 1, 0], [0, h - 1], [w - 1, h - 1]], np.float32)
        u = cv2.undistortPoints(corners.reshape(-1, 1, 2), K, D, **args).reshape(-1, 2)
        turned = np.column_stack([u, np.ones(4)]) @ Rk.T
        projected = (fc * turned[:, :2] / turned[:, 2:]).astype(np.float32).astype(np.float64)
        c0.append(np.array([(w - 1) / 2, (h - 1) / 2]) - projected.mean(0))
    c0 = np.array(c0)
    if zero_disparity:
        c0[:] = c0.mean(0)
    else:
        c0[:, 1 - idx] = c0[:, 1 - idx].mean()
    grid = np.array([(x * (w - 1) / 8, y * (h - 1) / 8) for y in range(9) for x in range(9)])
    inner, outer = [], []
    for (K, D, Rk), c in zip(cameras, c0):
        u = cv2.undistortPoints(grid.reshape(-1, 1, 2), K, D, R=Rk, P=k_of(fc, fc, *c),
                                **args).reshape(9, 9, 2)
        inner.append((u[:, 0, 0].max(), u[0, :, 1].max(), u[:, -1, 0].min(), u[-1, :, 1].min()))
        lo, hi = u.reshape(-1, 2).min(0), u.reshape(-1, 2).max(0)
        outer.append((lo[0], lo[1], hi[0], hi[1]))
    c = c0 * np.array([nw / w, nh / h])
    s = 1.0
    if alpha is not None:
        def scales(k, x0, y0, x1, y1):
            return [c[k, 0] / (c0[k, 0] - x0), c[k, 1] / (c0[k, 1] - y0),
                    (nw - 1 - c[k, 0]) / (x1 - c0[k, 0]), (nh - 1 - c[k, 1]) / (y1 - c0[k, 1])]
        s0 = max(max(scales(k, *r)) for k, r in enumerate(inner))
        s1 = min(min(scales(k, *r)) for k, r in enumerate(outer))
        s = s0 * (1 - alpha) + s1 * alpha
    f = fc * s
    P1 = np.array([[f, 0, c[0, 0], 0], [0, f, c[0, 1], 0], [0, 0, 1, 0]])
    P2 = np.array([[f, 0, c[1, 0], 0], [0, f, c[1, 1], 0], [0, 0, 1, 0]])
    P2[idx, 3] = t_idx * fc * s
    Q = np.array([[1, 0, 0, -c[0, 0]], [0, 1, 0, -c[0, 1]], [0, 0, 0, f],
                  [0, 0, -1 / t_idx, (c[0, idx] - c[1, idx]) / t_idx]])
    rois = []
    for k, (x0, y0, x1, y1) in enumerate(inner):
        x, y = int(np.ceil((x0 - c0[k, 0]) * s + c[k, 0])), int(np.ceil((y0 - c0[k, 1]) * s + c[k, 1]))
        rw, rh = int(np.floor((x1 - x0) * s)), int(np.floor((y1 - y0) * s))
        # cv::Rect's intersection with the new image.
        xa, ya = max(x, 0), max(y, 0)
        xb, yb = min(x + rw, nw), min(y + rh, nh)
        rois.append((xa, ya, xb - xa, yb - ya) if rw > 0 and rh > 0 and xb > xa and yb > ya
                    else (0, 0, 0, 0))
    return R1, R2, P1, P2, Q, rois[0], rois[1]


STANDARD_CASES = [(name, pair, alpha, new_size, zero_disparity)
                  for name in MILD for pair in PAIRS for alpha in [None, 0.0, 0.5, 1.0]
                  for new_size in [None, (800, 500)] for zero_disparity in [True, False]]


@pytest.mark.parametrize("name,pair,alpha,new_size,zero_disparity", STANDARD_CASES)
def test_the_rule_is_opencvs_and_vklens_computes_it_on_a_converged_inverse(
        name, pair, alpha, new_size, zero_disparity):
    K1, D1, K2, D2, size = MILD[name]
    rvec, T = PAIRS[pair]
    R = rotation(rvec)
    options = dict(alpha=alpha, new_size=new_size, zero_disparity=zero_disparity)
    theirs = cv2.stereoRectify(K1, D1, K2, D2, size, R, T.reshape(3, 1),
                               flags=flags_of(zero_disparity),
                               alpha=-1 if alpha is None else alpha,
                               newImageSize=new_size or (0, 0))
    # The rule as written above is OpenCV's: with OpenCV's default criteria it gives
    # cv2.stereoRectify's numbers to rounding (measured: 1e-15 of the largest entry).
    assert_matches(opencv_rule(K1, D1, K2, D2, size, R, T, **options), theirs, rtol=1e-13)
    # vklens computes the same rule on its converged inverse: the rule on a converged
    # cv2.undistortPoints, to rounding (measured: 2e-14 of the largest entry).
    left, right = (vklens.Camera.from_opencv(K1, D1, size),
                   vklens.Camera.from_opencv(K2, D2, size))
    ours = vklens.stereo_rectify(left, right, R, T, **options)
    converged = opencv_rule(K1, D1, K2, D2, size, R, T, criteria=CONVERGED, **options)
    assert_matches(ours, converged[:5], rtol=1e-12)
    # The ROIs within a pixel: at alpha 0 a side of the inner rectangle lands on the image's
    # edge, where rounding up a value within 1e-13 of a whole number decides a pixel.
    for got, want in [(ours.roi1, converged[5]), (ours.roi2, converged[6])]:
        assert np.abs(np.subtract(got, want)).max() <= 1, (got, want)


# How far OpenCV's default undistortPoints (5 iterations) stops short of converged on each
# pair's 9 × 9 grid, in pixels, and the agreement with cv2.stereoRectify that leaves (of the
# largest entry of P1, P2 and Q): measured 3.2e-6 px and 1.1e-8 on the plumb bob pair, 1.2e-3
# px and 2.5e-6 on the rational pair with prism and tilt.
FIVE_ITERATIONS = {"plumb_bob": (4e-6, 5e-8), "rational_prism_tilt": (1.5e-3, 1e-5)}


@pytest.mark.parametrize("name,pair,alpha,new_size,zero_disparity", STANDARD_CASES)
def test_standard_pair_matches_stereo_rectify(name, pair, alpha, new_size, zero_disparity):
    K1, D1, K2, D2, size = MILD[name]
    short, rtol = FIVE_ITERATIONS[name]
    w, h = size
    grid = np.array([(x * (w - 1) / 8, y * (h - 1) / 8) for y in range(9) for x in range(9)])
    for K, D in [(K1, D1), (K2, D2)]:
        default = cv2.undistortPoints(grid.reshape(-1, 1, 2), K, D)
        converged = cv2.undistortPoints(grid.reshape(-1, 1, 2), K, D, criteria=CONVERGED)
        assert np.abs(default - converged).max() * K[0, 0] <= short
    rvec, T = PAIRS[pair]
    R = rotation(rvec)
    left, right = (vklens.Camera.from_opencv(K1, D1, size),
                   vklens.Camera.from_opencv(K2, D2, size))
    theirs = cv2.stereoRectify(K1, D1, K2, D2, size, R, T.reshape(3, 1),
                               flags=flags_of(zero_disparity),
                               alpha=-1 if alpha is None else alpha,
                               newImageSize=new_size or (0, 0))
    ours = vklens.stereo_rectify(left, right, R, T, alpha=alpha, new_size=new_size,
                                 zero_disparity=zero_disparity)
    assert_matches(ours, theirs[:5], rtol=rtol)
    # The ROIs within a pixel: at alpha 0 a side of the inner rectangle lands on the image's
    # edge, where rounding up a value within 1e-13 of a whole number decides a pixel.
    for got, want in [(ours.roi1, theirs[5]), (ours.roi2, theirs[6])]:
        assert np.abs(np.subtract(got, want)).max() <= 1, (got, want)
    assert ours.vertical == (pair == "vertical")
    assert ours.baseline == pytest.approx(np.linalg.norm(T), rel=1e-14)
    # The rectified cameras are P1's and P2's 3×3 parts, at the new size.
    for cam, P in [(ours.left, ours.P1), (ours.right, ours.P2)]:
        assert cam.model == "opencv" and not np.any(cam.dist_coeffs)
        assert cam.size == (new_size or size)
        np.testing.assert_array_equal(cam.K, P[:, :3])


def test_a_strong_lens_differs_where_opencvs_five_iterations_have_not_converged(reference):
    # The webcam reference camera (k1 = -0.31) and a twin: OpenCV's default undistortPoints
    # leaves their corners short of converged.
    K1, D1 = k_d(reference["webcam_plumb_bob"])
    K2, D2 = K1 * np.array([[1.01, 1, 1], [1, 1.005, 1], [1, 1, 1]]), D1 * 0.95
    size = (1280, 720)
    rvec, T = PAIRS["horizontal"]
    R = rotation(rvec)
    left, right = (vklens.Camera.from_opencv(K1, D1, size),
                   vklens.Camera.from_opencv(K2, D2, size))
    for alpha in (None, 0.0, 1.0):
        theirs = cv2.stereoRectify(K1, D1, K2, D2, size, R, T.reshape(3, 1),
                                   alpha=-1 if alpha is None else alpha)
        # The rule as written here is OpenCV's on this lens too.
        assert_matches(opencv_rule(K1, D1, K2, D2, size, R, T, alpha), theirs, rtol=1e-13)
        ours = vklens.stereo_rectify(left, right, R, T, alpha=alpha)
        # vklens's rectified cameras are not OpenCV's ...
        assert np.abs(ours.P1 - theirs[2]).max() > 1e-5 * np.abs(theirs[2]).max()
        # ... they are the same rule on a converged undistortPoints.
        converged = opencv_rule(K1, D1, K2, D2, size, R, T, alpha, criteria=CONVERGED)
        assert_matches(ours, converged[:5], rtol=1e-12)


def fisheye_cameras(name, scale_fx=0.995, scale_d=1.02):
    c = json.loads((SHARED / "reference" / "fisheye" / f"{name}.json").read_text())
    K1 = k_of(c["fx"], c["fy"], c["cx"], c["cy"])
    D1 = np.array(c["dist_coeffs"], np.float64)
    K2 = K1 * np.array([[scale_fx, 1, 1], [1, 1, 1], [1, 1, 1]]) + np.array(
        [[0, 0, 3.5], [0, 0, -2.0], [0, 0, 0]])
    D2 = D1 * scale_d
    size = (c["width"], c["height"])
    cams = [vklens.Camera.from_opencv(K, D, size, fisheye=True) for K, D in [(K1, D1), (K2, D2)]]
    return cams, (K1, D1, K2, D2), size


@pytest.mark.parametrize("pair", PAIRS)
@pytest.mark.parametrize("balance", [0.0, 1.0])
@pytest.mark.parametrize("fov_scale", [1.0, 1.4])
@pytest.mark.parametrize("new_size", [None, (1920, 1080)])
@pytest.mark.parametrize("zero_disparity", [True, False])
def test_fisheye_pair_matches_fisheye_stereo_rectify(pair, balance, fov_scale, new_size,
                                                     zero_disparity):
    (left, right), (K1, D1, K2, D2), size = fisheye_cameras("fish_wide160")
    rvec, T = PAIRS[pair]
    R = rotation(rvec)
    theirs = cv2.fisheye.stereoRectify(K1, D1, K2, D2, size, R, T.reshape(3, 1),
                                       flags=flags_of(zero_disparity),
                                       newImageSize=new_size or (0, 0), balance=balance,
                                       fov_scale=fov_scale)
    ours = vklens.stereo_rectify(left, right, R, T, new_size=new_size,
                                 zero_disparity=zero_disparity, balance=balance,
                                 fov_scale=fov_scale)
    # The fisheye rule undistorts the four edge midpoints, where OpenCV's Newton on θ stops
    # at a step below 1e-8, after which it is within rounding of converged: measured 6e-13 of
    # the largest entry.
    assert_matches(ours, theirs, rtol=1e-11)
    # OpenCV's fisheye rectification always lays the baseline along the rows.
    assert not ours.vertical
    w, h = new_size or size
    assert ours.roi1 == ours.roi2 == (0, 0, w, h)
    assert ours.left.size == ours.right.size == (w, h)


def test_r_and_t_take_every_shape_cv2_takes():
    K1, D1, K2, D2, size = MILD["plumb_bob"]
    _, rtol = FIVE_ITERATIONS["plumb_bob"]
    left, right = (vklens.Camera.from_opencv(K1, D1, size),
                   vklens.Camera.from_opencv(K2, D2, size))
    rvec, T = PAIRS["vertical"]
    first = vklens.stereo_rectify(left, right, rvec, T, alpha=0.5)
    theirs = cv2.stereoRectify(K1, D1, K2, D2, size, rvec.reshape(3, 1), T.reshape(3, 1),
                               alpha=0.5)
    assert_matches(first, theirs[:5], rtol)
    for r in [rvec, rvec.reshape(3, 1), rvec.reshape(1, 3), list(rvec)]:
        for t in [T, T.reshape(3, 1), T.reshape(1, 3), list(T)]:
            assert_matches(vklens.stereo_rectify(left, right, r, t, alpha=0.5), first, 0)
    # The matrix, read through cv::Rodrigues as OpenCV reads it.
    assert_matches(vklens.stereo_rectify(left, right, rotation(rvec), T, alpha=0.5), first,
                   1e-12)
    # A matrix printed to six decimals is not quite a rotation: OpenCV takes the nearest one
    # (U Vᵀ of its SVD), and so does vklens.
    printed = np.round(rotation(rvec), 6)
    u, _, vt = np.linalg.svd(printed)
    nearest = vklens.stereo_rectify(left, right, u @ vt, T, alpha=0.5)
    assert_matches(vklens.stereo_rectify(left, right, printed, T, alpha=0.5), nearest, 1e-12)
    theirs = cv2.stereoRectify(K1, D1, K2, D2, size, printed, T.reshape(3, 1), alpha=0.5)
    assert_matches(nearest, theirs[:5], rtol)


def test_a_half_turn_and_a_tiny_turn_are_read_as_opencv_reads_them():
    # A camera mounted upside down beside the other (a half turn about the optical axis):
    # cv::Rodrigues picks the axis's sign, and so must vklens. A turn below 1e-5 rad OpenCV
    # reads as none (which moves the principal points by 1e-3 px here, far past `rtol`).
    K1, D1, K2, D2, size = MILD["plumb_bob"]
    _, rtol = FIVE_ITERATIONS["plumb_bob"]
    left, right = (vklens.Camera.from_opencv(K1, D1, size),
                   vklens.Camera.from_opencv(K2, D2, size))
    T = np.array([-0.12, 0.003, 0.001])
    for R in [np.diag([-1.0, -1.0, 1.0]), rotation([0, 0, np.pi - 1e-9]), rotation([4e-6, 0, 0])]:
        theirs = cv2.stereoRectify(K1, D1, K2, D2, size, R, T.reshape(3, 1))
        assert_matches(vklens.stereo_rectify(left, right, R, T), theirs[:5], rtol)


def test_refusals_name_the_keyword():
    K1, D1, K2, D2, size = MILD["plumb_bob"]
    std = vklens.Camera.from_opencv(K1, D1, size)
    (fish, fish2), _, _ = fisheye_cameras("fish_wide160")
    ucm = vklens.Camera(width=640, height=480, fx=300, fy=300, cx=320, cy=240, model="ucm",
                        alpha=0.6)
    rvec, T = PAIRS["horizontal"]
    cases = [
        ("right", "opencv_fisheye", lambda: vklens.stereo_rectify(std, fish, rvec, T)),
        ("left", "ucm", lambda: vklens.stereo_rectify(ucm, std, rvec, T)),
        ("right", "800×600",
         lambda: vklens.stereo_rectify(std, vklens.Camera.from_opencv(K2, D2, (800, 600)), rvec, T)),
        ("R", "shape", lambda: vklens.stereo_rectify(std, std, np.eye(2), T)),
        ("R", "rotation", lambda: vklens.stereo_rectify(std, std, np.diag([1.0, 1, -1]), T)),
        ("T", "shape", lambda: vklens.stereo_rectify(std, std, rvec, [1, 2])),
        ("T", "zero", lambda: vklens.stereo_rectify(std, std, rvec, [0, 0, 0])),
        ("alpha", "0..=1", lambda: vklens.stereo_rectify(std, std, rvec, T, alpha=1.5)),
        ("alpha", "balance", lambda: vklens.stereo_rectify(fish, fish2, rvec, T, alpha=0.5)),
        ("balance", "alpha", lambda: vklens.stereo_rectify(std, std, rvec, T, balance=0.5)),
        ("fov_scale", "alpha", lambda: vklens.stereo_rectify(std, std, rvec, T, fov_scale=2.0)),
        ("balance", "0..=1", lambda: vklens.stereo_rectify(fish, fish2, rvec, T, balance=3.0)),
        ("new_size", "", lambda: vklens.stereo_rectify(std, std, rvec, T, new_size=(0, 10))),
    ]
    for keyword, words, call in cases:
        with pytest.raises(vklens.InputError) as e:
            call()
        assert e.value.argument == keyword, (keyword, str(e.value))
        assert str(e.value).startswith(keyword) and words in str(e.value), str(e.value)


def test_the_result_is_read_only():
    K1, D1, K2, D2, size = MILD["plumb_bob"]
    left = vklens.Camera.from_opencv(K1, D1, size)
    s = vklens.stereo_rectify(left, left, *PAIRS["horizontal"])
    for name in ["R1", "R2", "P1", "P2", "Q", "roi1", "roi2", "left", "right"]:
        with pytest.raises(AttributeError):
            setattr(s, name, None)
    # The arrays are copies: changing one leaves the rectification as it was.
    s.P1[0, 0] = 0.0
    assert s.P1[0, 0] == s.left.fx > 0
    assert "horizontal" in repr(s)


def remapped(photo, K, D, R, P, size, fisheye):
    maps = cv2.fisheye.initUndistortRectifyMap if fisheye else cv2.initUndistortRectifyMap
    mx, my = maps(K, D, R, P, size, cv2.CV_32FC1)
    w, h = photo.shape[1], photo.shape[0]
    # Where OpenCV samples at least half a pixel inside the source, as vklens does.
    inside = (mx >= 0.5) & (my >= 0.5) & (mx <= w - 1.5) & (my <= h - 1.5)
    return cv2.remap(photo, mx, my, cv2.INTER_LINEAR), inside


def ros_matrix(text, key, rows, cols):
    import yaml
    return np.array(yaml.safe_load(text)[key]["data"], np.float64).reshape(rows, cols)


@pytest.mark.parametrize("model", ["standard", "fisheye"])
def test_the_command_writes_opencvs_rectification_and_rectified_pair(cli, tmp_path, model):
    if model == "standard":
        K1, D1, K2, D2, size = MILD["plumb_bob"]
        cams = [vklens.Camera.from_opencv(K, D, size) for K, D in [(K1, D1), (K2, D2)]]
        rectify, options = cv2.stereoRectify, {"alpha": 0.0}
        flags = ["--alpha", "0"]
        _, rtol = FIVE_ITERATIONS["plumb_bob"]
    else:
        cams, (K1, D1, K2, D2), size = fisheye_cameras("fish_wide160")
        rectify, options = cv2.fisheye.stereoRectify, {"balance": 0.5, "fov_scale": 1.2}
        flags = ["--balance", "0.5", "--fov-scale", "1.2"]
        rtol = 1e-11
    rvec, T = PAIRS["horizontal"]
    R1, R2, P1, P2 = rectify(K1, D1, K2, D2, size, rotation(rvec), T.reshape(3, 1),
                             flags=cv2.CALIB_ZERO_DISPARITY, **options)[:4]
    w, h = size
    photos = [smooth_image(w, h, 3), smooth_image(w, h, 3)[::-1, ::-1].copy()]
    paths = []
    for i, (cam, photo) in enumerate(zip(cams, photos)):
        cam.save(tmp_path / f"cam{i}.json")
        cv2.imwrite(str(tmp_path / f"photo{i}.png"), photo[:, :, ::-1])
        paths.append(str(tmp_path / f"cam{i}.json"))
    out = tmp_path / "rectified"
    r = subprocess.run(
        [str(cli), "stereo-rectify", "--camera", paths[0], "--camera", paths[1],
         "--rotation", ",".join(map(repr, rvec.tolist())),
         "--translation", ",".join(map(repr, T.tolist())),
         *flags, "--out", str(out), "--left", str(tmp_path / "photo0.png"),
         "--right", str(tmp_path / "photo1.png")],
        capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "baseline" in r.stderr
    for i, (K, D, R, P) in enumerate([(K1, D1, R1, P1), (K2, D2, R2, P2)]):
        side = ["left", "right"][i]
        text = (out / f"{side}.yaml").read_text()
        # camera_info's R and P are OpenCV's; its K and D the lens's own.
        np.testing.assert_allclose(ros_matrix(text, "rectification_matrix", 3, 3), R,
                                   rtol=0, atol=1e-14)
        np.testing.assert_allclose(ros_matrix(text, "projection_matrix", 3, 4), P, rtol=0,
                                   atol=rtol * np.abs(P).max())
        np.testing.assert_array_equal(ros_matrix(text, "camera_matrix", 3, 3), K)
        ours = cv2.imread(str(out / f"{side}.png"))[:, :, ::-1]
        theirs, inside = remapped(photos[i], K, D, R, P, size, model == "fisheye")
        valid = inside & (ours.sum(axis=2) > 0)
        d = np.abs(ours.astype(int) - theirs.astype(int))[valid]
        # Within a grey level: vklens samples in f32 where cv2.remap quantizes its maps to 1/32
        # px, which moves a few pixels across a rounding step (measured: mean 5e-4, largest 1).
        assert valid.mean() > 0.8 and d.mean() <= 0.01 and d.max() <= 1, (d.mean(), d.max())
