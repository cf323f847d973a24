"""vklens.compat against OpenCV itself: every function called with the arguments its cv2
counterpart gets, and its answer compared with cv2's computed here: maps, images, points,
new cameras and stereo rectifications, each accepted input form and output argument."""

import json

import cv2
import numpy as np
import pytest

import vklens
from vklens import compat
from vklens.compat import fisheye

from conftest import SHARED, smooth_image

REFERENCE_CASES = {c["name"]: c for c in json.loads(
    (SHARED / "reference" / "opencv_standard_model.json").read_text())["cases"]}

# The GPU tests run on the shared device, whose validation layer fails the run on any
# message.
pytestmark = pytest.mark.usefixtures("device")

# cv2's undistortPoints iterated until it has converged (its default stops after 5 steps).
TIGHT = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)

def k_of(fx, fy, cx, cy):
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def scaled(name, s):
    """A shared reference camera with its image scaled by ``s`` (pixel centres kept: OpenCV's
    convention), so that images stay small; its distortion is the reference's."""
    c = REFERENCE_CASES[name]
    K = k_of(c["fx"] * s, c["fy"] * s, (c["cx"] + 0.5) * s - 0.5, (c["cy"] + 0.5) * s - 0.5)
    return K, np.array(c["dist_coeffs"]), (round(c["width"] * s), round(c["height"] * s))


# A mild lens, on which OpenCV's 5 iterations have converged (checked where it matters).
MILD_K = k_of(300.0, 305.0, 161.3, 119.6)
MILD_D = np.array([-0.05, 0.01, 0.001, -0.0015, 0.002])
SIZE = (320, 240)
# The webcam reference (k1 = -0.31), a quarter of its 1280×720.
STRONG_K, STRONG_D, STRONG_SIZE = scaled("webcam_plumb_bob", 0.25)
STRONG_D = STRONG_D[:5]
# fish_wide160 at a fifth of its 1600×1200.
FISH_K = k_of(540.31 * 0.2, 540.12 * 0.2, 799.64 * 0.2 - 0.4, 601.27 * 0.2 - 0.4)
FISH_D = np.array([0.034712, -0.011925, 0.003214, -0.000417])

STEREO_R, _ = cv2.Rodrigues(np.array([0.01, -0.03, 0.005]))
STEREO_T = np.array([[-0.12], [0.002], [0.001]])
RIGHT_K = MILD_K * np.array([[1.01, 1, 1], [1, 1.005, 1], [1, 1, 1]]) + np.array(
    [[0, 0, 2.5], [0, 0, -1.5], [0, 0, 0]])
RIGHT_D = MILD_D * 0.95


def grey_levels(dtype):
    """One grey level of an 8-bit image in the units of ``dtype`` (conftest's smooth_image
    spans 0..65535 for uint16 and 0..1 for floats)."""
    return {np.uint8: 1.0, np.uint16: 257.0, np.float32: 1 / 255, np.float64: 1 / 255}[dtype]


def positions(map1, map2):
    """Source positions of a CV_16SC2 pair: the whole pixel plus the table index's fractions."""
    x = map1[..., 0] + (map2 & 31) / 32.0
    y = map1[..., 1] + (map2 >> 5) / 32.0
    return x, y


# ---------------------------------------------------------------------------------------------
# Constants


def test_constants_are_cv2s():
    assert compat.CALIB_ZERO_DISPARITY == fisheye.CALIB_ZERO_DISPARITY == cv2.CALIB_ZERO_DISPARITY
    assert compat.CV_32FC1 == cv2.CV_32FC1
    # OpenCV 4's codes; OpenCV 5 moved the channel count (its CV_32FC2 is 37), and compat reads
    # either (the map tests pass cv2's own).
    depth_shift = 3 if cv2.CV_32FC2 == 13 else 5
    assert cv2.CV_32FC2 == cv2.CV_32F + (1 << depth_shift) and compat.CV_32FC2 == cv2.CV_32F + 8
    assert cv2.CV_16SC2 == cv2.CV_16S + (1 << depth_shift) and compat.CV_16SC2 == cv2.CV_16S + 8


# ---------------------------------------------------------------------------------------------
# initUndistortRectifyMap


def _standard_map_cases():
    new05, _ = cv2.getOptimalNewCameraMatrix(MILD_K, MILD_D, SIZE, 0.5)
    new_size = (400, 300)
    wide, _ = cv2.getOptimalNewCameraMatrix(MILD_K, MILD_D, SIZE, 1.0, new_size)
    R1, _, P1, _ = cv2.stereoRectify(MILD_K, MILD_D, RIGHT_K, RIGHT_D, SIZE, STEREO_R, STEREO_T,
                                     alpha=0)[:4]
    return {
        "alpha0.5": (MILD_K, MILD_D, None, new05, SIZE),
        "new_size": (MILD_K, MILD_D, None, wide, new_size),
        "default_new_camera": (MILD_K, MILD_D, None, None, SIZE),
        "rectified": (MILD_K, MILD_D, R1, P1, SIZE),
        "strong": (STRONG_K, STRONG_D, None, STRONG_K, STRONG_SIZE),
    }


STANDARD_MAPS = _standard_map_cases()


def check_maps(ours, theirs, m1type, valid):
    """``ours`` is cv2's layout of cv2's maps, their positions within 1e-3 px (float maps) or
    OpenCV's own fixed-point rounding of vklens's float maps (CV_16SC2), where ``valid``."""
    assert [None if m is None else (m.shape, m.dtype) for m in ours] == \
        [None if m is None else (m.shape, m.dtype) for m in theirs]
    if m1type == "CV_32FC1":
        assert np.abs(ours[0] - theirs[0])[valid].max() <= 1e-3
        assert np.abs(ours[1] - theirs[1])[valid].max() <= 1e-3
    elif m1type == "CV_32FC2":
        assert ours[1] is None and np.abs(ours[0] - theirs[0])[valid].max() <= 1e-3
    else:
        # cv2 rounds the double position to 1/32 px, vklens its float32 map: one step apart
        # at most, where the two straddle a rounding boundary.
        ox, oy = positions(*ours)
        tx, ty = positions(*theirs)
        assert np.abs(ox - tx)[valid].max() <= 1 / 32 + 1e-9
        assert np.abs(oy - ty)[valid].max() <= 1 / 32 + 1e-9
        assert np.mean(((ox != tx) | (oy != ty))[valid]) < 0.01
    # Elsewhere NO_SOURCE in every layout.
    if m1type in ("CV_32FC1", "CV_32FC2"):
        assert (np.reshape(ours[0], valid.shape + (-1,)) == compat.NO_SOURCE)[~valid].all()
    else:
        assert (ours[0] == -32768)[~valid].all() and (ours[1] == 0)[~valid].all()


@pytest.mark.parametrize("case", list(STANDARD_MAPS))
def test_init_undistort_rectify_map_equals_cv2(case):
    K, D, R, P, size = STANDARD_MAPS[case]
    floats = compat.initUndistortRectifyMap(K, D, R, P, size, compat.CV_32FC1)
    valid = floats[0] != compat.NO_SOURCE
    assert valid.all(), "the mild lens has a source for every pixel"
    for m1type in ["CV_32FC1", "CV_32FC2", "CV_16SC2", -1]:
        theirs = cv2.initUndistortRectifyMap(K, D, R, P, size, getattr(cv2, str(m1type), m1type))
        # compat's own constant and the installed cv2's give the same maps.
        for code in {getattr(compat, str(m1type), m1type), getattr(cv2, str(m1type), m1type)}:
            ours = compat.initUndistortRectifyMap(K, D, R, P, size, code)
            check_maps(ours, theirs, "CV_16SC2" if m1type == -1 else m1type, valid)
            if m1type in ("CV_16SC2", -1):
                # Exactly OpenCV's conversion of the float maps.
                want = cv2.convertMaps(floats[0], floats[1], cv2.CV_16SC2)
                np.testing.assert_array_equal(ours[0], want[0])
                np.testing.assert_array_equal(ours[1], want[1])


def test_init_undistort_rectify_map_writes_output_arguments_as_cv2():
    K, D, R, P, size = STANDARD_MAPS["alpha0.5"]
    h, w = size[1], size[0]
    written = []
    for make in [compat.initUndistortRectifyMap, cv2.initUndistortRectifyMap]:
        map1, map2 = np.empty((h, w), np.float32), np.empty((h, w), np.float32)
        got = make(K, D, R, P, size, cv2.CV_32FC1, map1, map2)
        assert got[0] is map1 and got[1] is map2
        # The wrong dtype is replaced, not converted into.
        wrong = np.empty((h, w), np.float64)
        got = make(K, D, R, P, size, cv2.CV_32FC1, wrong)
        assert got[0] is not wrong and got[0].dtype == np.float32
        map1, map2 = np.empty((h, w, 2), np.int16), np.empty((h, w), np.uint16)
        got = make(K, D, R, P, size, cv2.CV_16SC2, map1, map2)
        assert got[0] is map1 and got[1] is map2
        written.append(got)
    check_maps(written[0], written[1], "CV_16SC2", np.ones((h, w), bool))


@pytest.mark.parametrize("shape", ["flat", "row", "column", "list"])
def test_distortion_vector_shapes_are_read_as_cv2(shape):
    K, D, R, P, size = STANDARD_MAPS["alpha0.5"]
    given = {"flat": D, "row": D.reshape(1, -1), "column": D.reshape(-1, 1), "list": list(D)}[shape]
    mx, my = compat.initUndistortRectifyMap(K, given, R, P, size, cv2.CV_32FC1)
    tx, ty = cv2.initUndistortRectifyMap(K, D.reshape(1, -1), R, P, size, cv2.CV_32FC1)
    assert np.abs(mx - tx).max() <= 1e-3 and np.abs(my - ty).max() <= 1e-3


def test_no_source_pixels_are_filled_by_remap():
    # k1 = -0.5 folds over at an ideal radius of 0.82 (a distorted 0.54); a new camera of short
    # focal length sees past it in its corners. cv2's maps send those pixels back into the
    # image (the folded lens's answer), vklens's to NO_SOURCE.
    K, D, size = MILD_K, np.array([-0.5, 0.0, 0.0, 0.0, 0.0]), SIZE
    P = k_of(110.0, 110.0, 159.5, 119.5)
    photo = smooth_image(*size)
    floats = compat.initUndistortRectifyMap(K, D, None, P, size, cv2.CV_32FC1)
    theirs = cv2.initUndistortRectifyMap(K, D, None, P, size, cv2.CV_32FC1)
    nowhere = floats[0] == compat.NO_SOURCE
    assert 0.05 < nowhere.mean() < 0.8
    np.testing.assert_array_equal(nowhere, floats[1] == compat.NO_SOURCE)
    # Exactly where the new camera's ray lies past the fold (r² = 2/3), to the precision of the
    # lens's domain table.
    v, u = np.mgrid[0:size[1], 0:size[0]]
    r = np.hypot((u - P[0, 2]) / P[0, 0], (v - P[1, 2]) / P[1, 1])
    fold = np.sqrt(2 / 3)
    disagree = nowhere != (r > fold)
    assert disagree.mean() < 1e-3 and (np.abs(r - fold)[disagree] < 1e-3).all()
    valid = ~nowhere
    assert np.abs(floats[0] - theirs[0])[valid].max() <= 1e-3
    # Inside the image in cv2's maps (folded content), outside in vklens's.
    inside = ((theirs[0] > 0) & (theirs[0] < size[0] - 1)
              & (theirs[1] > 0) & (theirs[1] < size[1] - 1))
    assert (inside & nowhere).sum() > 1000
    for m1type in [cv2.CV_32FC1, cv2.CV_32FC2, cv2.CV_16SC2]:
        m1, m2 = compat.initUndistortRectifyMap(K, D, None, P, size, m1type)
        for border in [0, 7]:
            out = cv2.remap(photo, m1, m2, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                            borderValue=(border,) * 3)
            assert (out[nowhere] == border).all()
            ref = cv2.remap(photo, *theirs, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                            borderValue=(border,) * 3)
            assert np.abs(out.astype(int) - ref)[valid].mean() < 0.15
            assert np.abs(out.astype(int) - ref)[nowhere & inside].mean() > 20


# ---------------------------------------------------------------------------------------------
# undistort


@pytest.mark.parametrize("alpha", [None, 0.0, 0.5, 1.0])
def test_undistort_equals_cv2(alpha):
    K, D = STRONG_K, STRONG_D
    w, h = STRONG_SIZE
    new = None if alpha is None else cv2.getOptimalNewCameraMatrix(K, D, (w, h), alpha)[0]
    photo = smooth_image(w, h)
    ours = compat.undistort(photo, K, D, None, new)
    theirs = cv2.undistort(photo, K, D, None, new)
    assert ours.shape == theirs.shape and ours.dtype == theirs.dtype
    d = np.abs(ours.astype(int) - theirs)
    # cv2 samples at 1/32 px, vklens at the exact position: a fraction of a grey level, a few
    # on the steepest slopes. The black border blends over the last pixel as in cv2 (alpha 1
    # has long stretches of it).
    assert d.mean() <= 0.15 and d.max() <= 6, (d.mean(), d.max())
    assert (theirs == 0).mean() == pytest.approx((ours == 0).mean(), abs=2e-3)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int16, np.float32, np.float64])
@pytest.mark.parametrize("channels", [None, 1, 2, 3, 4, 5])
def test_undistort_takes_every_dtype_and_channel_count_as_cv2(dtype, channels):
    K, D = STRONG_K, STRONG_D
    w, h = STRONG_SIZE
    planes = np.dstack([smooth_image(w, h, 4, np.float64), smooth_image(w, h, 1, np.float64)])
    if dtype == np.int16:
        photo, unit = np.rint((planes - 0.5) * 60000).astype(np.int16), 60000 / 255
    else:
        base = dtype if dtype != np.float64 else np.float32
        unit = grey_levels(base)
        scale = {np.uint8: 255, np.uint16: 65535}.get(dtype, 1)
        photo = np.rint(planes * scale).astype(dtype) if scale > 1 else planes.astype(dtype)
    photo = photo[:, :, 0] if channels is None else photo[:, :, :channels]
    ours = compat.undistort(photo, K, D)
    theirs = cv2.undistort(photo, K, D)
    assert ours.shape == theirs.shape and ours.dtype == theirs.dtype
    d = np.abs(ours.astype(np.float64) - theirs) / unit
    assert d.mean() <= 0.15 and d.max() <= 6, (d.mean(), d.max())


def test_undistort_writes_dst_as_cv2():
    K, D = STRONG_K, STRONG_D
    w, h = STRONG_SIZE
    photo = smooth_image(w, h)
    for make in [compat.undistort, cv2.undistort]:
        dst = np.empty((h, w, 3), np.uint8)
        assert make(photo, K, D, dst) is dst
        wrong = np.empty((h, w, 3), np.float32)
        got = make(photo, K, D, wrong)
        assert got is not wrong and got.dtype == np.uint8
        grey = photo[:, :, :1]
        flat = np.empty((h, w), np.uint8)
        assert make(grey, K, D, flat) is flat
    assert np.abs(dst.astype(int) - cv2.undistort(photo, K, D)).mean() <= 0.15
    assert np.abs(flat.astype(int) - cv2.undistort(grey, K, D)).mean() <= 0.15


def test_undistort_reuses_its_warper():
    K, D = STRONG_K, STRONG_D
    w, h = STRONG_SIZE
    photo = smooth_image(w, h)
    theirs = cv2.undistort(photo, K, D)
    first = compat.undistort(photo, K, D)
    before = compat.cache_info()
    # The same values in other containers and shapes are the same key.
    again = compat.undistort(photo, K.tolist(), D.reshape(1, -1))
    after = compat.cache_info()
    assert after.hits == before.hits + 1 and after.misses == before.misses
    np.testing.assert_array_equal(first, again)
    assert np.abs(again.astype(int) - theirs).mean() <= 0.15


# ---------------------------------------------------------------------------------------------
# undistortPoints


def pixels(size, n=200, seed=7):
    rng = np.random.default_rng(seed)
    return rng.uniform([0, 0], [size[0] - 1, size[1] - 1], (n, 2))


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("form", ["N12", "1N2", "N2", "one"])
def test_undistort_points_shapes_and_dtypes_are_cv2s(form, dtype):
    uv = pixels(SIZE).astype(dtype)
    src = {"N12": uv.reshape(-1, 1, 2), "1N2": uv.reshape(1, -1, 2), "N2": uv, "one": uv[0]}[form]
    ours = compat.undistortPoints(src, MILD_K, MILD_D)
    theirs = cv2.undistortPoints(src, MILD_K, MILD_D, criteria=TIGHT)
    assert ours.shape == theirs.shape and ours.dtype == theirs.dtype
    if dtype == np.float64:
        assert np.abs(ours - theirs).max() * MILD_K[0, 0] <= 1e-6
    else:
        # Both round the same double answer to float32.
        np.testing.assert_allclose(ours, theirs, rtol=2e-7, atol=1e-7)
    # A list is read as its numbers (cv2 wants an array).
    listed = compat.undistortPoints(np.asarray(src, np.float64).tolist(), MILD_K, MILD_D)
    assert listed.dtype == np.float64 and listed.shape == theirs.shape


@pytest.mark.parametrize("n", [4, 5, 8, 12, 14])
@pytest.mark.parametrize("shape", ["flat", "row", "column"])
def test_undistort_points_with_r_and_p_equal_cv2(n, shape):
    # prism_tilt's coefficients cut to n, as calibrations of each length hold them.
    D = np.array(REFERENCE_CASES["prism_tilt"]["dist_coeffs"])[:n]
    D = {"flat": D, "row": D.reshape(1, -1), "column": D.reshape(-1, 1)}[shape]
    R1, _, P1, _ = cv2.stereoRectify(MILD_K, MILD_D, RIGHT_K, RIGHT_D, SIZE, STEREO_R, STEREO_T,
                                     alpha=0)[:4]
    src = pixels(SIZE).reshape(-1, 1, 2)
    for R, P in [(None, None), (R1, None), (None, MILD_K), (R1, P1), (R1, P1[:, :3])]:
        ours = compat.undistortPoints(src, MILD_K, D, R=R, P=P)
        theirs = cv2.undistortPoints(src, MILD_K, D, R=R, P=P, criteria=TIGHT)
        px = 1.0 if P is not None else MILD_K[0, 0]
        assert np.abs(ours - theirs).max() * px <= 1e-6


@pytest.mark.parametrize("D", [None, np.array([]), np.zeros(5)], ids=["None", "empty", "zeros"])
def test_no_distortion_is_none_or_empty_as_in_cv2(D):
    src = pixels(SIZE).reshape(-1, 1, 2)
    ours = compat.undistortPoints(src, MILD_K, D, P=MILD_K)
    theirs = cv2.undistortPoints(src, MILD_K, D, P=MILD_K)
    assert np.abs(ours - theirs).max() <= 1e-9
    new, roi = compat.getOptimalNewCameraMatrix(MILD_K, D, SIZE, 0.5)
    want, want_roi = cv2.getOptimalNewCameraMatrix(MILD_K, D, SIZE, 0.5)
    np.testing.assert_allclose(new, want, rtol=1e-9, atol=1e-12)
    assert roi == want_roi


def test_undistort_points_is_converged_where_cv2s_default_is_not():
    # The webcam reference at full size: at its corner pixel cv2's 5 default iterations stop
    # 1.6 px short; vklens's answer is cv2's own iteration run until it has converged.
    c = REFERENCE_CASES["webcam_plumb_bob"]
    K, D = k_of(c["fx"], c["fy"], c["cx"], c["cy"]), np.array(c["dist_coeffs"])
    corners = np.array([[0.0, 0.0], [c["width"] - 1.0, 0.0], [0.0, c["height"] - 1.0],
                        [c["width"] - 1.0, c["height"] - 1.0]]).reshape(-1, 1, 2)
    ours = compat.undistortPoints(corners, K, D, P=K)
    default = cv2.undistortPoints(corners, K, D, P=K)
    converged = cv2.undistortPoints(corners, K, D, P=K, criteria=TIGHT)
    assert np.abs(ours - converged).max() <= 1e-6
    assert np.abs(default - converged).max() > 1.0
    # The converged points are the ones that project back onto the corners.
    rays = np.dstack([cv2.undistortPoints(ours, K, np.zeros(5)), np.ones((4, 1))])
    back, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, D)
    assert np.abs(back - corners).max() <= 1e-6


def test_undistort_points_is_nan_where_the_lens_has_no_inverse():
    # k1 = -0.5 bends no pixel beyond a distorted radius of 0.544: pixels past it have no
    # undistorted point. cv2 answers one anyway, which does not project back.
    D = np.array([-0.5, 0.0, 0.0, 0.0, 0.0])
    src = pixels(SIZE, 400).reshape(-1, 1, 2)
    ours = compat.undistortPoints(src, MILD_K, D)
    theirs = cv2.undistortPoints(src, MILD_K, D, criteria=TIGHT)
    radius = np.hypot(*((src.reshape(-1, 2) - MILD_K[:2, 2]) / np.diag(MILD_K)[:2]).T)
    rmax = 2 / 3 * np.sqrt(2 / 3)  # r (1 - 0.5 r²) at its top, r² = 2/3
    nan = np.isnan(ours).any(axis=2).ravel()
    np.testing.assert_array_equal(nan, radius > rmax + 1e-9)
    assert 0.02 < nan.mean() < 0.9
    assert np.abs(ours - theirs)[~nan].max() * MILD_K[0, 0] <= 1e-6
    rays = np.dstack([theirs, np.ones((len(src), 1))])
    back, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), MILD_K, D)
    assert np.abs(back - src).max(axis=2).ravel()[nan].min() > 1e-3


def test_undistort_points_writes_dst_as_cv2():
    src = pixels(SIZE).reshape(-1, 1, 2)
    for make in [compat.undistortPoints, cv2.undistortPoints]:
        dst = np.empty((len(src), 1, 2))
        assert make(src, MILD_K, MILD_D, dst) is dst
        wrong = np.empty((len(src), 2))
        assert make(src, MILD_K, MILD_D, wrong) is not wrong
        single = np.empty((len(src), 1, 2), np.float32)
        got = make(src, MILD_K, MILD_D, single)
        assert got is not single and got.dtype == np.float64
    assert np.abs(dst - cv2.undistortPoints(src, MILD_K, MILD_D, criteria=TIGHT)).max() <= 1e-8


# ---------------------------------------------------------------------------------------------
# getOptimalNewCameraMatrix


@pytest.mark.parametrize("alpha", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("new_size", [None, (400, 300)])
@pytest.mark.parametrize("centred", [False, True])
def test_get_optimal_new_camera_matrix_equals_cv2(alpha, new_size, centred):
    # cv2's 5 iterations have converged on the mild lens's grid: the cameras agree.
    grid = np.stack(np.meshgrid(np.linspace(0, SIZE[0] - 1, 9), np.linspace(0, SIZE[1] - 1, 9)),
                    -1).reshape(-1, 1, 2)
    five = cv2.undistortPoints(grid, MILD_K, MILD_D, P=MILD_K)
    assert np.abs(five - cv2.undistortPoints(grid, MILD_K, MILD_D, P=MILD_K,
                                             criteria=TIGHT)).max() < 1e-6
    ours, roi = compat.getOptimalNewCameraMatrix(MILD_K, MILD_D, SIZE, alpha, new_size, centred)
    theirs, their_roi = cv2.getOptimalNewCameraMatrix(MILD_K, MILD_D, SIZE, alpha, new_size,
                                                      centred)
    assert ours.shape == (3, 3) and ours.dtype == theirs.dtype
    np.testing.assert_allclose(ours, theirs, rtol=1e-6, atol=1e-9)
    assert isinstance(roi, tuple) and roi == their_roi


def test_get_optimal_new_camera_matrix_is_converged_where_cv2s_is_not():
    # The webcam reference. cv2's rule undistorts a 9 × 9 grid spanning the image and fits the
    # rectangle inside its edge rows and columns (alpha 0) or around them all (alpha 1) to the
    # new image's edges; its 5 iterations leave the corner pixels 1.6 px short.
    c = REFERENCE_CASES["webcam_plumb_bob"]
    K, D, size = k_of(c["fx"], c["fy"], c["cx"], c["cy"]), np.array(c["dist_coeffs"]), (
        c["width"], c["height"])
    grid = np.stack(np.meshgrid(np.linspace(0, size[0] - 1, 9), np.linspace(0, size[1] - 1, 9)),
                    -1).reshape(-1, 1, 2)
    edges = np.array([0, 0, size[0] - 1, size[1] - 1])

    def sides(camera, criteria):
        """The rectangles' left, top, right and bottom in ``camera``'s pixels."""
        u = cv2.undistortPoints(grid, K, D, P=camera, **criteria).reshape(9, 9, 2)
        inner = (u[:, 0, 0].max(), u[0, :, 1].max(), u[:, -1, 0].min(), u[-1, :, 1].min())
        outer = (u[..., 0].min(), u[..., 1].min(), u[..., 0].max(), u[..., 1].max())
        return np.array(inner), np.array(outer)

    converged = {"criteria": TIGHT}
    for alpha in (0, 1):
        ours, _ = compat.getOptimalNewCameraMatrix(K, D, size, alpha)
        theirs, _ = cv2.getOptimalNewCameraMatrix(K, D, size, alpha)
        # cv2's camera puts the rectangle on the image's edges as its 5 iterations see it ...
        assert np.abs(sides(theirs, {})[alpha] - edges).max() < 1e-6
        # ... not where the converged points lie: a third of a pixel off, its focal length
        # 0.05 % to 0.2 % ...
        assert np.abs(sides(theirs, converged)[alpha] - edges).max() > 0.25
        assert np.abs(ours[0, 0] / theirs[0, 0] - 1) > 4e-4
        # ... and vklens's puts the converged rectangle there.
        assert np.abs(sides(ours, converged)[alpha] - edges).max() < 1e-6


# ---------------------------------------------------------------------------------------------
# fisheye


def fisheye_new(balance, new_size=(0, 0), fov_scale=1.0):
    return cv2.fisheye.estimateNewCameraMatrixForUndistortRectify(
        FISH_K, FISH_D, SIZE, np.eye(3), balance=balance, new_size=new_size, fov_scale=fov_scale)


@pytest.mark.parametrize("balance", [0.0, 1.0])
@pytest.mark.parametrize("new_size", [(0, 0), (400, 300)])
@pytest.mark.parametrize("fov_scale", [1.0, 1.5])
def test_fisheye_estimate_new_camera_matrix_equals_cv2(balance, new_size, fov_scale):
    theirs = fisheye_new(balance, new_size, fov_scale)
    for R in [np.eye(3), None, np.zeros(3), np.zeros((3, 1))]:
        ours = fisheye.estimateNewCameraMatrixForUndistortRectify(
            FISH_K, FISH_D.reshape(1, 4), SIZE, R, balance=balance, new_size=new_size,
            fov_scale=fov_scale)
        np.testing.assert_allclose(ours, theirs, rtol=1e-9, atol=1e-12)
    P = np.empty((3, 3))
    assert fisheye.estimateNewCameraMatrixForUndistortRectify(FISH_K, FISH_D, SIZE, np.eye(3), P,
                                                              balance) is P


def test_fisheye_estimate_new_camera_matrix_refuses_a_rotation():
    R = cv2.Rodrigues(np.array([0.0, 0.05, 0.0]))[0]
    theirs = cv2.fisheye.estimateNewCameraMatrixForUndistortRectify(FISH_K, FISH_D, SIZE, R)
    assert np.abs(theirs - fisheye_new(0.0)).max() > 1.0, "cv2's answer depends on R"
    with pytest.raises(vklens.InputError) as e:
        fisheye.estimateNewCameraMatrixForUndistortRectify(FISH_K, FISH_D, SIZE, R)
    assert e.value.argument == "R"


def _fisheye_map_cases():
    R1, _, P1, _ = cv2.fisheye.stereoRectify(FISH_K, FISH_D, FISH_K * [[0.995], [1], [1]],
                                             FISH_D * 1.02, SIZE, STEREO_R, STEREO_T,
                                             cv2.CALIB_ZERO_DISPARITY)[:4]
    return {
        "balance0": (None, fisheye_new(0.0), SIZE),
        "balance1": (np.eye(3), fisheye_new(1.0), SIZE),
        "new_size": (None, fisheye_new(0.5, (400, 300)), (400, 300)),
        "rectified_rodrigues": (cv2.Rodrigues(R1)[0], P1, SIZE),
        "identity_P": (None, None, SIZE),
    }


FISHEYE_MAPS = _fisheye_map_cases()


@pytest.mark.parametrize("case", list(FISHEYE_MAPS))
def test_fisheye_init_undistort_rectify_map_equals_cv2(case):
    R, P, size = FISHEYE_MAPS[case]
    floats = fisheye.initUndistortRectifyMap(FISH_K, FISH_D, R, P, size, compat.CV_32FC1)
    # Every pixel has a source: even the identity camera's, which sees out to 89.9° off the
    # axis, lie where this lens's polynomial still grows.
    valid = floats[0] != compat.NO_SOURCE
    assert valid.all()
    for m1type in ["CV_32FC1", "CV_16SC2", -1]:
        # cv2.fisheye reads m1type <= 0 as CV_16SC2 but leaves those maps unwritten (OpenCV
        # 5.1): its CV_16SC2 maps are the answer -1 means.
        theirs = cv2.fisheye.initUndistortRectifyMap(FISH_K, FISH_D, R, P, size,
                                                     getattr(cv2, str(m1type), cv2.CV_16SC2))
        ours = fisheye.initUndistortRectifyMap(FISH_K, FISH_D, R, P, size,
                                               getattr(compat, str(m1type), m1type))
        check_maps(ours, theirs, "CV_16SC2" if m1type == -1 else m1type, valid)
    # cv2.fisheye refuses CV_32FC2; compat gives it, the float maps side by side.
    xy, none = fisheye.initUndistortRectifyMap(FISH_K, FISH_D, R, P, size, compat.CV_32FC2)
    assert none is None
    np.testing.assert_array_equal(xy, np.dstack(floats))


@pytest.mark.parametrize("case", ["balance0", "balance1", "new_size", "identity_P"])
def test_fisheye_undistort_image_equals_cv2(case):
    _, P, size = FISHEYE_MAPS[case]
    photo = smooth_image(*SIZE)
    new_size = None if size == SIZE else size
    ours = fisheye.undistortImage(photo, FISH_K, FISH_D, Knew=P, new_size=new_size)
    theirs = cv2.fisheye.undistortImage(photo, FISH_K, FISH_D, Knew=P, new_size=new_size)
    assert ours.shape == theirs.shape and ours.dtype == theirs.dtype
    d = np.abs(ours.astype(int) - theirs)
    assert d.mean() <= 0.15 and d.max() <= 6, (d.mean(), d.max())
    undistorted = np.empty_like(theirs)
    assert fisheye.undistortImage(photo, FISH_K, FISH_D, undistorted, P,
                                  new_size) is undistorted
    np.testing.assert_array_equal(undistorted, ours)


@pytest.mark.parametrize("dtype", [np.uint16, np.float32])
def test_fisheye_undistort_image_takes_other_dtypes(dtype):
    photo = smooth_image(*SIZE, channels=4, dtype=dtype)
    P = FISHEYE_MAPS["balance1"][1]
    ours = fisheye.undistortImage(photo, FISH_K, FISH_D, Knew=P)
    theirs = cv2.fisheye.undistortImage(photo, FISH_K, FISH_D, Knew=P)
    assert ours.shape == theirs.shape and ours.dtype == theirs.dtype
    d = np.abs(ours.astype(np.float64) - theirs) / grey_levels(dtype)
    assert d.mean() <= 0.15 and d.max() <= 6


@pytest.mark.parametrize("form", ["N12", "1N2", "N2"])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_fisheye_undistort_points_equals_cv2(form, dtype):
    rng = np.random.default_rng(11)
    uv = rng.uniform([0, 0], [SIZE[0] - 1, SIZE[1] - 1], (300, 2))
    # cv2.fisheye clips the distorted angle at π/2, where it answers another point; inside,
    # its default criteria (Newton until a step moves θ < 1e-8) have converged on this lens,
    # and vklens agrees with them as with a tight criteria.
    theta_d = np.hypot(*((uv - FISH_K[:2, 2]) / np.diag(FISH_K)[:2]).T)
    inside = theta_d < np.pi / 2
    assert 0.5 < inside.mean() < 1
    R1, _, P1, _ = cv2.fisheye.stereoRectify(FISH_K, FISH_D, FISH_K, FISH_D, SIZE, STEREO_R,
                                             STEREO_T, 0)[:4]
    for R, P in [(None, None), (cv2.Rodrigues(R1)[0].ravel(), None), (None, FISH_K),
                 (R1, P1)]:
        arr = uv.astype(dtype)
        src = {"N12": arr.reshape(-1, 1, 2), "1N2": arr.reshape(1, -1, 2), "N2": arr}[form]
        ours = fisheye.undistortPoints(src, FISH_K, FISH_D, R=R, P=P)
        # cv2.fisheye takes N×1 and 1×N two-channel arrays only.
        cv_src = src if form != "N2" else arr.reshape(-1, 1, 2)
        want_shape = cv2.fisheye.undistortPoints(cv_src, FISH_K, FISH_D, R=R, P=P).shape
        assert ours.shape == want_shape and ours.dtype == dtype
        for criteria in [None, TIGHT]:
            args = {} if criteria is None else {"criteria": criteria}
            theirs = cv2.fisheye.undistortPoints(arr.astype(np.float64).reshape(-1, 1, 2), FISH_K,
                                                 FISH_D, R=R, P=P, **args).reshape(-1, 2)
            got = ours.reshape(-1, 2).astype(np.float64)
            known = ~np.isnan(got).any(axis=1)
            compared = known & inside
            assert compared.mean() > 0.5
            if dtype == np.float64:
                px = 1.0 if P is not None else FISH_K[0, 0]
                assert np.abs(got - theirs)[compared].max() * px <= 1e-6
            else:
                np.testing.assert_allclose(got[compared], theirs[compared], rtol=2e-7, atol=1e-7)
            # NaN only where the ray points at or behind the (turned) image plane.
            assert known[inside & (theta_d < 1.2)].all()


def test_fisheye_undistort_points_writes_undistorted():
    src = pixels(SIZE, 50).reshape(1, -1, 2)
    written = []
    for make in [fisheye.undistortPoints, cv2.fisheye.undistortPoints]:
        out = np.empty((1, 50, 2))
        assert make(src, FISH_K, FISH_D, out, P=FISH_K) is out
        wrong = np.empty((50, 1, 2))
        assert make(src, FISH_K, FISH_D, wrong, P=FISH_K) is not wrong
        written.append(out)
    theta_d = np.hypot(*((src.reshape(-1, 2) - FISH_K[:2, 2]) / np.diag(FISH_K)[:2]).T)
    inside = (theta_d < np.pi / 2) & ~np.isnan(written[0][0]).any(axis=1)
    assert inside.mean() > 0.5
    assert np.abs(written[0] - written[1])[0][inside].max() <= 1e-6


def test_fisheye_skew_is_applied_as_cv2_fisheye_projects_it():
    # cv2.fisheye.projectPoints applies the skew α = K[0][1] / fx; cv2's undistortPoints ignores
    # it and lands beside the ray, vklens's comes back to it.
    K = FISH_K.copy()
    K[0, 1] = 0.002 * K[0, 0]
    rng = np.random.default_rng(5)
    rays = np.column_stack([rng.uniform(-1, 1, (50, 2)), np.ones(50)])
    uv, _ = cv2.fisheye.projectPoints(rays.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, FISH_D,
                                      alpha=0.002)
    ours = fisheye.undistortPoints(uv, K, FISH_D).reshape(-1, 2)
    theirs = cv2.fisheye.undistortPoints(uv, K, FISH_D).reshape(-1, 2)
    assert np.abs(ours - rays[:, :2]).max() <= 1e-9
    assert np.abs(theirs - rays[:, :2]).max() > 1e-3


# ---------------------------------------------------------------------------------------------
# stereoRectify


def assert_rectification(ours, theirs, rtol):
    for a, b in zip(ours[:5], theirs[:5]):
        assert a.shape == b.shape and a.dtype == b.dtype
        np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol * np.abs(b).max())


@pytest.mark.parametrize("alpha", [-1, 0.0, 1.0])
@pytest.mark.parametrize("flags", [0, cv2.CALIB_ZERO_DISPARITY])
def test_stereo_rectify_equals_cv2(alpha, flags):
    for R, T in [(STEREO_R, STEREO_T), (cv2.Rodrigues(STEREO_R)[0], STEREO_T.ravel())]:
        ours = compat.stereoRectify(MILD_K, MILD_D, RIGHT_K, RIGHT_D, SIZE, R, T, flags=flags,
                                    alpha=alpha)
        theirs = cv2.stereoRectify(MILD_K, MILD_D, RIGHT_K, RIGHT_D, SIZE, R, STEREO_T,
                                   flags=flags, alpha=alpha)
        assert len(ours) == 7
        assert_rectification(ours, theirs, 1e-6)
        assert ours[5:] == theirs[5:] and all(isinstance(r, tuple) for r in ours[5:])
    outs = [np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 4)), np.empty((3, 4)),
            np.empty((4, 4))]
    got = compat.stereoRectify(MILD_K, MILD_D, RIGHT_K, RIGHT_D, SIZE, STEREO_R, STEREO_T, *outs,
                               flags=flags, alpha=alpha, newImageSize=(400, 300))
    assert all(g is o for g, o in zip(got, outs))
    theirs = cv2.stereoRectify(MILD_K, MILD_D, RIGHT_K, RIGHT_D, SIZE, STEREO_R, STEREO_T,
                               flags=flags, alpha=alpha, newImageSize=(400, 300))
    assert_rectification(got, theirs, 1e-6)


@pytest.mark.parametrize("balance", [0.0, 1.0])
@pytest.mark.parametrize("flags", [0, cv2.CALIB_ZERO_DISPARITY])
def test_fisheye_stereo_rectify_equals_cv2(balance, flags):
    K2, D2 = FISH_K * [[0.995], [1], [1]], FISH_D * 1.02
    for R, T in [(STEREO_R, STEREO_T), (cv2.Rodrigues(STEREO_R)[0], STEREO_T.ravel())]:
        ours = fisheye.stereoRectify(FISH_K, FISH_D, K2, D2, SIZE, R, T, flags, balance=balance)
        theirs = cv2.fisheye.stereoRectify(FISH_K, FISH_D, K2, D2, SIZE, R, T, flags,
                                           balance=balance)
        assert len(ours) == 5
        assert_rectification(ours, theirs, 1e-6)


# ---------------------------------------------------------------------------------------------
# Bad input


def test_bad_input_names_the_argument():
    photo = np.zeros((SIZE[1], SIZE[0], 3), np.uint8)
    cases = [
        ("cameraMatrix", lambda: compat.undistort(photo, np.eye(2), MILD_D)),
        ("distCoeffs", lambda: compat.undistort(photo, MILD_K, np.zeros(6))),
        ("src", lambda: compat.undistort(photo.astype(np.int32), MILD_K, MILD_D)),
        ("src", lambda: compat.undistort(photo.tolist(), MILD_K, MILD_D)),
        ("newCameraMatrix", lambda: compat.undistort(photo, MILD_K, MILD_D, None, np.eye(4))),
        ("m1type", lambda: compat.initUndistortRectifyMap(MILD_K, MILD_D, None, MILD_K, SIZE,
                                                          cv2.CV_16SC1)),
        ("R", lambda: compat.initUndistortRectifyMap(MILD_K, MILD_D, np.zeros(3), MILD_K, SIZE,
                                                     cv2.CV_32FC1)),
        ("size", lambda: compat.initUndistortRectifyMap(MILD_K, MILD_D, None, MILD_K, (0, 5),
                                                        cv2.CV_32FC1)),
        ("src", lambda: compat.undistortPoints(np.zeros((5, 3)), MILD_K, MILD_D)),
        ("R", lambda: compat.undistortPoints(np.zeros((5, 2)), MILD_K, MILD_D,
                                             R=np.array([0.1, 0.0, 0.0]))),
        ("P", lambda: compat.undistortPoints(np.zeros((5, 2)), MILD_K, MILD_D, P=np.eye(4))),
        ("alpha", lambda: compat.getOptimalNewCameraMatrix(MILD_K, MILD_D, SIZE, 1.5)),
        ("alpha", lambda: compat.getOptimalNewCameraMatrix(MILD_K, MILD_D, SIZE, "a")),
        ("newImgSize", lambda: compat.getOptimalNewCameraMatrix(MILD_K, MILD_D, SIZE, 0.5,
                                                                (-4, 3))),
        ("D", lambda: fisheye.undistortImage(photo, FISH_K, np.zeros(5))),
        ("balance", lambda: fisheye.estimateNewCameraMatrixForUndistortRectify(
            FISH_K, FISH_D, SIZE, None, balance=2.0)),
        ("fov_scale", lambda: fisheye.estimateNewCameraMatrixForUndistortRectify(
            FISH_K, FISH_D, SIZE, None, fov_scale=0.0)),
        ("Knew", lambda: fisheye.undistortImage(photo, FISH_K, FISH_D,
                                                Knew=[[1, 0.5, 0], [0, 1, 0], [0, 0, 1]])),
    ]
    for name, call in cases:
        with pytest.raises(vklens.InputError) as e:
            call()
        assert e.value.argument == name, (name, str(e.value))
        assert str(e.value).startswith(name), str(e.value)
        assert isinstance(e.value, ValueError)
    # cv2 refuses the same calls (except the vklens-only numbers checks it does not make).
    with pytest.raises(cv2.error):
        cv2.initUndistortRectifyMap(MILD_K, MILD_D, np.zeros(3), MILD_K, SIZE, cv2.CV_32FC1)
    with pytest.raises(cv2.error):
        cv2.initUndistortRectifyMap(MILD_K, MILD_D, None, MILD_K, SIZE, cv2.CV_16SC1)
    with pytest.raises(cv2.error):
        cv2.undistort(photo.astype(np.int32), MILD_K, MILD_D)
