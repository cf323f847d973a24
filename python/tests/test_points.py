"""Points through the camera model, against OpenCV in the same process and against the Rust
library (its command line) for where the inverse is invalid."""

import json
import subprocess

import cv2
import numpy as np
import pytest

import vklens
from conftest import camera_of, k_d

CASES = ["seed_fig2", "seed_fig1_barrel", "webcam_plumb_bob", "rational_wide", "prism_tilt", "strong_pincushion"]


def grid(case):
    return np.array([p["undistorted_normalized"] for p in case["points"]])


@pytest.mark.parametrize("name", CASES)
def test_distort_points_equals_opencv(reference, name):
    case = reference[name]
    cam = camera_of(case)
    K, D = k_d(case)
    xy = grid(case)
    ours = cam.distort_points(xy)
    obj = np.hstack([xy, np.ones((len(xy), 1))])
    theirs, _ = cv2.projectPoints(obj, np.zeros(3), np.zeros(3), K, D)
    assert ours.shape == (len(xy), 2) and ours.dtype == np.float64
    assert np.max(np.abs(ours - theirs.reshape(-1, 2))) <= 1e-9
    # and the stored ground truth of the reference data
    stored = np.array([p["distorted_pixel"] for p in case["points"]])
    assert np.max(np.abs(ours - stored)) <= 1e-9


@pytest.mark.parametrize("name", CASES)
def test_project_points_equals_opencv_with_a_pose(reference, name):
    case = reference[name]
    cam = camera_of(case)
    K, D = k_d(case)
    rng = np.random.default_rng(7)
    pts = np.column_stack([rng.uniform(-1, 1, 400), rng.uniform(-0.8, 0.8, 400), rng.uniform(1.5, 4, 400)])
    rvec, tvec = np.array([0.05, -0.1, 0.02]), np.array([0.1, -0.05, 0.3])
    theirs, _ = cv2.projectPoints(pts, rvec, tvec, K, D)
    # OpenCV's own shapes for rvec and tvec are accepted
    for r, t in [(rvec, tvec), (rvec.reshape(3, 1), tvec.reshape(1, 3)), (list(rvec), tuple(tvec))]:
        ours = cam.project_points(pts, rvec=r, tvec=t)
        assert np.max(np.abs(ours - theirs.reshape(-1, 2))) <= 1e-9


def test_project_points_behind_the_camera_are_nan(reference):
    cam = camera_of(reference["seed_fig2"])
    uv = cam.project_points(np.array([[0.1, 0.1, 2.0], [0.1, 0.1, 0.0], [0.1, 0.1, -2.0]]))
    assert np.isfinite(uv[0]).all()
    assert np.isnan(uv[1:]).all()


@pytest.mark.parametrize("name", CASES)
def test_undistort_points_equals_opencv_200_iterations_and_rust_validity(reference, cli, name, tmp_path):
    case = reference[name]
    cam = camera_of(case)
    uv = np.array([p["distorted_pixel"] for p in case["points"]])
    ours = cam.undistort_points(uv)
    # NaN exactly where the Rust library says invalid
    path = tmp_path / "cam.json"
    cam.save(path)
    out = subprocess.run([cli, "points", "undistort", "--camera", path], input=json.dumps(uv.tolist()),
                         capture_output=True, text=True, check=True).stdout
    rust = json.loads(out)
    rust_invalid = np.array([p is None for p in rust])
    assert (np.isnan(ours).all(axis=1) == rust_invalid).all()
    assert (np.isnan(ours).any(axis=1) == np.isnan(ours).all(axis=1)).all()
    valid = ~rust_invalid
    assert np.allclose(ours[valid], np.array([p for p in rust if p is not None]), atol=1e-12, rtol=0)
    # inside the valid domain: OpenCV's 200-iteration inverse to 1e-6 px wherever that
    # iteration converged (it reprojects onto the pixel; it stalls at some valid points of the
    # folding rational_wide lens, where Newton does not)
    K, D = k_d(case)
    theirs = cv2.undistortPoints(uv.reshape(-1, 1, 2), K, D, None, None, None,
                                  criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-14)).reshape(-1, 2)
    f = np.array([case["fx"], case["fy"]])
    converged = np.abs(cam.distort_points(theirs) - uv).max(axis=1) < 1e-9
    both = valid & converged
    assert both.sum() > 0.5 * len(uv)
    assert (np.abs(ours[both] - theirs[both]) * f).max() <= 1e-6
    # every valid answer is a preimage: it projects back onto its pixel (where a lens folds
    # over, the pixel's in-domain preimage, not the reference point beyond the fold)
    assert np.abs(cam.distort_points(ours[valid]) - uv[valid]).max() <= 1e-6
    if name != "rational_wide":
        assert both.sum() == valid.sum()


def test_undistort_methods(reference):
    cam = camera_of(reference["seed_fig2"])
    uv = cam.distort_points(np.array([[0.2, -0.1], [0.4, 0.3]]))
    # Heikkilä's closed form is an approximation (Lambers et al.'s Eq. 2): close, not exact
    for m, tol in [("newton", 1e-12), ("fixed-point:50", 1e-9), ("heikkila", 1e-3)]:
        xy = cam.undistort_points(uv, method=m)
        assert np.allclose(xy, [[0.2, -0.1], [0.4, 0.3]], atol=tol, rtol=0), m
    with pytest.raises(vklens.InputError, match="method"):
        cam.undistort_points(uv, method="bisection")


def test_opencv_shapes_of_k_and_d(reference):
    case = reference["prism_tilt"]
    K, D = k_d(case)
    size = (case["width"], case["height"])
    cams = [vklens.Camera.from_opencv(K, d, size) for d in (D, D.reshape(1, -1), D.reshape(-1, 1), list(D))]
    assert all(c == cams[0] for c in cams)
    cam = cams[0]
    assert (cam.width, cam.height) == size and isinstance(cam.width, int)
    assert cam.K.shape == (3, 3) and cam.K.dtype == np.float64 and (cam.K == K).all()
    assert cam.dist_coeffs.shape == (14,) and (cam.dist_coeffs == D).all()
    five = vklens.Camera.from_opencv(K, D[:5], size)
    assert five.dist_coeffs.shape == (5,)
    assert (cam.fx, cam.fy, cam.cx, cam.cy) == (case["fx"], case["fy"], case["cx"], case["cy"])


def test_every_calibration_file_loads_to_its_parameters(calibration_files):
    index = json.loads((calibration_files / "index.json").read_text())
    for entry in index["cameras"]:
        for f in entry["files"]:
            cam = vklens.Camera.load(calibration_files / f)
            assert (cam.width, cam.height) == (entry["width"], entry["height"]), f
            assert (cam.fx, cam.fy, cam.cx, cam.cy) == (entry["fx"], entry["fy"], entry["cx"], entry["cy"]), f
            n = len(cam.dist_coeffs)
            assert list(cam.dist_coeffs) == entry["dist_coeffs"][:n] and not any(entry["dist_coeffs"][n:]), f


def test_dict_save_load_and_pickle_round_trip(reference, tmp_path):
    import pickle

    cam = camera_of(reference["prism_tilt"])
    d = cam.to_dict()
    assert d["fx"] == cam.fx and len(d["dist_coeffs"]) == 14
    assert vklens.Camera.from_dict(d) == cam
    cam.save(tmp_path / "c.json")
    assert vklens.Camera.load(tmp_path / "c.json") == cam
    assert pickle.loads(pickle.dumps(cam)) == cam
    assert "fx=" in repr(cam) and "1024×768" in repr(cam)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(fx=-400.0), "fx"),
        (dict(fy=float("nan")), "fy"),
        (dict(dist_coeffs=[0.1] * 7), "dist_coeffs"),
        (dict(dist_coeffs=[float("nan"), 0, 0, 0]), "dist_coeffs"),
        (dict(width=-5), "width"),
        (dict(dist_coeffs="abc"), "dist_coeffs"),
    ],
)
def test_bad_camera_parameters_name_the_argument(kwargs, name):
    args = dict(width=800, height=600, fx=400.0, fy=400.0, cx=399.5, cy=299.5, dist_coeffs=[0, 0, 0, 0])
    args.update(kwargs)
    with pytest.raises(vklens.InputError, match=name):
        vklens.Camera(**args)


def test_bad_points_and_k_name_the_argument(reference):
    cam = camera_of(reference["seed_fig2"])
    with pytest.raises(vklens.InputError, match="xy"):
        cam.distort_points(np.zeros((4, 3)))
    with pytest.raises(vklens.InputError, match="points_3d") as e:
        cam.project_points(np.zeros((4, 2)))
    assert e.value.argument == "points_3d"
    with pytest.raises(vklens.InputError, match="rvec"):
        cam.project_points(np.zeros((4, 3)), rvec=np.zeros(4))
    with pytest.raises(vklens.InputError, match="K"):
        vklens.Camera.from_opencv(np.eye(2), np.zeros(5), (800, 600))
    with pytest.raises(vklens.InputError, match="K"):
        vklens.Camera.from_opencv(np.array([[400, 0, 1], [0, 400, 1], [0, 0, np.nan]]), np.zeros(5), (8, 6))
    # The argument each refusal is about, as this call names it.
    K = np.array([[400.0, 0, 399.5], [0, 400.0, 299.5], [0, 0, 1]])
    for args, argument in (((K, np.zeros(7), (800, 600)), "D"), ((K, [np.nan, 0, 0, 0], (800, 600)), "D"),
                           ((K, np.zeros(5), (0, 600)), "size"),
                           ((np.array([[400.0, 1, 399.5], [0, 400, 299.5], [0, 0, 1]]), np.zeros(5), (8, 6)), "K")):
        with pytest.raises(vklens.InputError) as e:
            vklens.Camera.from_opencv(*args)
        assert e.value.argument == argument and str(e.value).startswith(argument + ": "), str(e.value)
    with pytest.raises(vklens.InputError) as e:
        vklens.Camera(800, 600, 400.0, 400.0, 399.5, 299.5, dist_coeffs=np.zeros(7))
    assert e.value.argument == "dist_coeffs"
    with pytest.raises(vklens.InputError, match="D"):
        vklens.Camera.from_opencv(np.eye(3), np.zeros((2, 5)), (800, 600))
    with pytest.raises(vklens.IoError, match="nowhere.yml"):
        vklens.Camera.load("/nowhere.yml")
    # the kinds are also the standard exceptions
    assert issubclass(vklens.InputError, ValueError) and issubclass(vklens.GpuError, RuntimeError)


@pytest.mark.parametrize("shape", [(2,), (7, 2), (7, 1, 2), (3, 4, 2), (0, 2)])
def test_points_keep_any_leading_shape(reference, shape):
    cam = camera_of(reference["webcam_plumb_bob"])
    rng = np.random.default_rng(11)
    xy = rng.uniform(-0.4, 0.4, shape)
    uv = cam.distort_points(xy)
    assert uv.shape == shape and uv.dtype == np.float64
    back = cam.undistort_points(uv)
    assert back.shape == shape
    np.testing.assert_allclose(back, xy, atol=1e-12)
    rays = cam.unproject_points(uv)
    assert rays.shape == shape[:-1] + (3,)
    pts = np.concatenate([xy, np.ones(shape[:-1] + (1,))], axis=-1) * 2.0
    assert cam.project_points(pts).shape == shape
    # The same numbers as the flat call, point for point.
    np.testing.assert_array_equal(uv.reshape(-1, 2), cam.distort_points(xy.reshape(-1, 2)))
    with pytest.raises(vklens.InputError, match="uv"):
        cam.undistort_points(np.zeros(shape[:-1] + (3,)))


@pytest.mark.parametrize("model", ["standard", "fisheye"])
def test_points_89_5_to_89_9_degrees_off_axis_round_trip(model):
    # As Kornia's round-trip tests do: undistort_points(distort_points(p)) == p up to the last
    # tenth of a degree before 90°, where the point still has a preimage.
    if model == "standard":
        cam = vklens.Camera(width=640, height=480, fx=500, fy=500, cx=320, cy=240,
                            dist_coeffs=[0.02, 0.001, 0.0, 0.0])
    else:
        cam = vklens.Camera(width=640, height=480, fx=300, fy=300, cx=320, cy=240,
                            model="opencv_fisheye", dist_coeffs=[0.01, -0.002, 0.0005, -0.0001])
    rng = np.random.default_rng(5)
    theta = np.radians(rng.uniform(89.5, 89.9, 200))
    phi = rng.uniform(0, 2 * np.pi, 200)
    xy = np.stack([np.tan(theta) * np.cos(phi), np.tan(theta) * np.sin(phi)], axis=1)
    back = cam.undistort_points(cam.distort_points(xy))
    assert not np.isnan(back).any()
    np.testing.assert_allclose(back, xy, rtol=1e-9)
