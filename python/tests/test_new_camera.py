"""Camera.optimal_new_camera against OpenCV itself: cv2.getOptimalNewCameraMatrix for the
standard model, cv2.fisheye.estimateNewCameraMatrixForUndistortRectify for the fisheye, and
Camera.from_opencv(..., fisheye=True) against cv2.fisheye."""

import json
import os

import cv2
import numpy as np
import pytest

import vklens

from conftest import SHARED

FISH = SHARED / "reference" / "fisheye"
REFERENCE = {c["name"]: c for c in json.loads(
    (SHARED / "reference" / "opencv_standard_model.json").read_text())["cases"]}

# OpenCV's undistortPoints until it has converged (its default stops after 5 iterations).
CONVERGED = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)


def k_of(fx, fy, cx, cy, skew=0.0):
    return np.array([[fx, skew, cx], [0, fy, cy], [0, 0, 1.0]])


# Standard-model cameras on which OpenCV's 5 iterations have converged at the grid pixels: the
# paper's thin-prism-and-tilt reference camera, and mild lenses of every coefficient group.
MILD = [
    ("prism_tilt", k_of(*(REFERENCE["prism_tilt"][k] for k in ("fx", "fy", "cx", "cy"))),
     np.array(REFERENCE["prism_tilt"]["dist_coeffs"]),
     (REFERENCE["prism_tilt"]["width"], REFERENCE["prism_tilt"]["height"])),
    ("k1k2p1p2", k_of(600, 610, 330.2, 236.9), np.array([-0.05, 0.01, 0.001, -0.0015]), (640, 480)),
    ("pincushion", k_of(600, 610, 330.2, 236.9), np.array([0.05, 0.0, 0.0, 0.0, 0.0]), (640, 480)),
    ("rational", k_of(600, 610, 330.2, 236.9),
     np.array([0.1, -0.02, 0.0005, 0.0004, 0.001, 0.08, -0.01, 0.0]), (640, 480)),
    ("prism12", k_of(600, 610, 330.2, 236.9),
     np.array([-0.08, 0.012, 0, 0, 0, 0, 0, 0, 0.001, -0.0005, 0.0008, 0.0002]), (640, 480)),
]


def grid(size):
    """getUndistortRectangles' 9 × 9 grid of pixels spanning the image."""
    w, h = size
    return np.array([(x * (w - 1) / 8, y * (h - 1) / 8) for y in range(9) for x in range(9)],
                    np.float64).reshape(-1, 1, 2)


def rule(K, D, size, alpha, criteria=None):
    """getOptimalNewCameraMatrix's rule (no centring, no new size) on cv2.undistortPoints with
    the given criteria: checked below to be OpenCV's own with its default ones."""
    w, h = size
    args = {} if criteria is None else {"criteria": criteria}
    u = cv2.undistortPoints(grid(size), K, D, **args).reshape(9, 9, 2)
    inner = (u[:, 0, 0].max(), u[0, :, 1].max(), u[:, -1, 0].min(), u[-1, :, 1].min())
    lo, hi = u.reshape(-1, 2).min(0), u.reshape(-1, 2).max(0)
    outer = (lo[0], lo[1], hi[0], hi[1])

    def fit(x0, y0, x1, y1):
        fx, fy = (w - 1) / (x1 - x0), (h - 1) / (y1 - y0)
        return np.array([fx, fy, -fx * x0, -fy * y0])
    return fit(*inner) * (1 - alpha) + fit(*outer) * alpha


def params(M):
    return np.array([M[0, 0], M[1, 1], M[0, 2], M[1, 2]])


@pytest.mark.parametrize("name,K,D,size", MILD, ids=[m[0] for m in MILD])
@pytest.mark.parametrize("alpha", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("new_size", [None, (1024, 600)])
@pytest.mark.parametrize("centred", [False, True])
def test_standard_model_matches_get_optimal_new_camera_matrix(name, K, D, size, alpha, new_size,
                                                                centred):
    # Both inverses converged on this camera: OpenCV's 5 iterations agree with 200 of them.
    assert np.abs(cv2.undistortPoints(grid(size), K, D)
                  - cv2.undistortPoints(grid(size), K, D, criteria=CONVERGED)).max() < 1e-6
    cam = vklens.Camera.from_opencv(K, D, size)
    M, roi = cv2.getOptimalNewCameraMatrix(K, D, size, alpha, new_size or (0, 0), centred)
    new, got_roi = cam.optimal_new_camera(alpha, new_size, centred)
    np.testing.assert_allclose(params(new.K), params(M), rtol=1e-6)
    assert got_roi == tuple(roi)
    assert new.size == (new_size or size)
    assert new.model == "opencv" and not np.any(new.dist_coeffs)
    assert new.K[0, 1] == 0


def test_a_strong_lens_differs_where_opencvs_five_iterations_have_not_converged():
    # The webcam reference camera: k1 = -0.31, whose corners OpenCV's default undistortPoints
    # leaves short of converged.
    c = REFERENCE["webcam_plumb_bob"]
    K, D, size = k_of(c["fx"], c["fy"], c["cx"], c["cy"]), np.array(c["dist_coeffs"]), (
        c["width"], c["height"])
    cam = vklens.Camera.from_opencv(K, D, size)
    for alpha in (0.0, 1.0):
        M, _ = cv2.getOptimalNewCameraMatrix(K, D, size, alpha)
        # The rule as written here is OpenCV's: with OpenCV's default criteria it gives
        # OpenCV's camera to the last bit.
        np.testing.assert_allclose(rule(K, D, size, alpha), params(M), rtol=1e-12)
        new, _ = cam.optimal_new_camera(alpha)
        # vklens's camera is not OpenCV's ...
        assert np.abs(params(new.K) / params(M) - 1).max() > 1e-5
        # ... it is the same rule on a converged undistortPoints.
        np.testing.assert_allclose(params(new.K), rule(K, D, size, alpha, CONVERGED), rtol=1e-9)


FISHEYES = ["fish_wide160", "fish_equidistant185"]


def fisheye_k_d(name):
    c = json.loads((FISH / f"{name}.json").read_text())
    return (k_of(c["fx"], c["fy"], c["cx"], c["cy"], c.get("alpha", 0.0) * c["fx"]),
            np.array(c["dist_coeffs"], np.float64), (c["width"], c["height"]))


@pytest.mark.parametrize("name", FISHEYES)
@pytest.mark.parametrize("balance", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("fov_scale", [1.0, 1.6])
@pytest.mark.parametrize("new_size", [None, (1920, 1080)])
def test_fisheye_matches_estimate_new_camera_matrix(name, balance, fov_scale, new_size):
    # fish_equidistant185's side midpoints lie outside its image circle: OpenCV clips their
    # distorted radius at π/2, and so does vklens.
    K, D, size = fisheye_k_d(name)
    cam = vklens.Camera.load(FISH / f"{name}.json")
    P = cv2.fisheye.estimateNewCameraMatrixForUndistortRectify(
        K, D, size, np.eye(3), balance=balance, new_size=new_size or (0, 0), fov_scale=fov_scale)
    new, roi = cam.optimal_new_camera(balance=balance, fov_scale=fov_scale, new_size=new_size)
    np.testing.assert_allclose(params(new.K), params(P), rtol=1e-6)
    assert new.size == (new_size or size) and new.model == "opencv"
    # OpenCV gives the fisheye no ROI; vklens's holds pixels that see the lens image: each
    # samples inside it (cv2.fisheye.distortPoints of the pixel's ray).
    x, y, w, h = roi
    assert w > 0 and h > 0
    xs, ys = np.meshgrid(np.linspace(x + 1, x + w - 2, 25), np.linspace(y + 1, y + h - 2, 25))
    pts = np.stack([xs.ravel(), ys.ravel()], 1).reshape(-1, 1, 2)
    src = cv2.fisheye.distortPoints(
        cv2.undistortPoints(pts, new.K, np.zeros(5)), K, D).reshape(-1, 2)
    assert np.all((src > -0.5) & (src < np.array(size) - 0.5))


def test_fisheye_cameras_opencv_has_no_answer_for_are_refused():
    # fish_fold's side midpoints lie past its fold: OpenCV's undistortPoints gives up there
    # (-1e6) and its "camera" has a focal length below a thousandth of a pixel.
    K, D, size = fisheye_k_d("fish_fold")
    P = cv2.fisheye.estimateNewCameraMatrixForUndistortRectify(K, D, size, np.eye(3), balance=0)
    assert P[0, 0] < 1e-2
    cam = vklens.Camera.load(FISH / "fish_fold.json")
    with pytest.raises(vklens.InputError) as e:
        cam.optimal_new_camera(balance=0.0)
    assert e.value.argument == "camera" and "pinhole" in str(e.value)


def test_from_opencv_fisheye_is_cv2_fisheye():
    K, D, size = fisheye_k_d("fish_skew170")
    cam = vklens.Camera.from_opencv(K, D, size, fisheye=True)
    assert cam.model == "opencv_fisheye"
    assert cam == vklens.Camera.load(FISH / "fish_skew170.json")
    np.testing.assert_array_equal(cam.K, K)
    rng = np.random.default_rng(5)
    pts = np.column_stack([rng.uniform(-1, 1, (50, 2)), rng.uniform(0.5, 2, 50)])
    want, _ = cv2.fisheye.projectPoints(pts.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, D,
                                        alpha=K[0, 1] / K[0, 0])
    np.testing.assert_allclose(cam.project_points(pts), want.reshape(-1, 2), atol=1e-9)
    # Without fisheye=True four coefficients stay the standard model's k1 k2 p1 p2.
    std = vklens.Camera.from_opencv(k_of(K[0, 0], K[1, 1], K[0, 2], K[1, 2]), D, size)
    assert std.model == "opencv"
    # cv2.fisheye has exactly four coefficients.
    with pytest.raises(vklens.InputError) as e:
        vklens.Camera.from_opencv(K, np.append(D, 0.0), size, fisheye=True)
    assert e.value.argument == "D"
    with pytest.raises(vklens.InputError) as e:
        vklens.Camera.from_opencv(k_of(-1, 300, 400, 300), D, size, fisheye=True)
    assert e.value.argument == "K"


def test_refusals_name_the_keyword():
    name, K, D, size = MILD[1]
    std = vklens.Camera.from_opencv(K, D, size)
    fish = vklens.Camera.load(FISH / "fish_wide160.json")
    cases = [
        ("alpha", lambda: std.optimal_new_camera(-0.1)),
        ("alpha", lambda: std.optimal_new_camera(1.5)),
        ("alpha", lambda: std.optimal_new_camera(float("nan"))),
        ("alpha", lambda: std.optimal_new_camera()),
        ("balance", lambda: std.optimal_new_camera(0.5, balance=0.5)),
        ("balance", lambda: std.optimal_new_camera(balance=0.5)),
        ("alpha", lambda: fish.optimal_new_camera(0.5)),
        ("balance", lambda: fish.optimal_new_camera(balance=2.0)),
        ("fov_scale", lambda: fish.optimal_new_camera(balance=0.5, fov_scale=0.0)),
        ("fov_scale", lambda: std.optimal_new_camera(0.5, fov_scale=2.0)),
        ("center_principal_point",
         lambda: fish.optimal_new_camera(balance=0.5, center_principal_point=True)),
        ("new_size", lambda: std.optimal_new_camera(0.5, new_size=(0, 100))),
        ("new_size", lambda: std.optimal_new_camera(0.5, new_size=(-5, 100))),
    ]
    for keyword, call in cases:
        with pytest.raises(vklens.InputError) as e:
            call()
        assert e.value.argument == keyword, (keyword, str(e.value))
        assert str(e.value).startswith(keyword), str(e.value)
    # The wrong model's message says which rule the camera takes.
    with pytest.raises(vklens.InputError, match="opencv_fisheye.*balance"):
        fish.optimal_new_camera(0.5)
    with pytest.raises(vklens.InputError, match="exclusive"):
        std.optimal_new_camera(0.5, balance=0.5)


def test_the_new_camera_undistorts_like_cv2():
    # The camera feeds vklens's own undistort as its output camera, as the pair feeds
    # cv2.initUndistortRectifyMap: the maps agree where both have a source.
    name, K, D, size = MILD[1]
    cam = vklens.Camera.from_opencv(K, D, size)
    new, (x, y, w, h) = cam.optimal_new_camera(0.0)
    M, _ = cv2.getOptimalNewCameraMatrix(K, D, size, 0.0)
    map_x, map_y = cv2.initUndistortRectifyMap(K, D, None, M, size, cv2.CV_32FC1)
    ys, xs = np.mgrid[y:y + h:7, x:x + w:7]
    pix = np.stack([xs.ravel(), ys.ravel()], 1).astype(np.float64)
    rays = np.column_stack([(pix - new.K[:2, 2]) / np.diag(new.K)[:2], np.ones(len(pix))])
    ours = cam.project_points(rays)
    theirs = np.stack([map_x[ys.ravel(), xs.ravel()], map_y[ys.ravel(), xs.ravel()]], 1)
    # cv2's maps are float32 of a camera 1e-6 apart: a thousandth of a pixel.
    np.testing.assert_allclose(ours, theirs, atol=2e-3)
