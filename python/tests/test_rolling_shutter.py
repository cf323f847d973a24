"""Camera.project_points through a rolling shutter: the global shutter against
cv2.projectPoints, the rolling shutter against a numpy solve written here (the pose at s from
cv2.Rodrigues' log and exp, the pixel from OpenCV's own projectPoints, g scanned on a fine grid
and its first sign change bisected)."""

import json
import tomllib

import cv2
import numpy as np
import pytest

import vklens
from conftest import REPO

READOUTS = ["top_to_bottom", "bottom_to_top", "left_to_right", "right_to_left"]

# A 1920×1080 standard-model camera and a 200° fisheye (both in OpenCV), a double sphere (not).
STANDARD = dict(width=1920, height=1080, fx=1100.0, fy=1090.0, cx=959.5, cy=539.5,
                dist_coeffs=[-0.12, 0.05, 0.0008, -0.0005, -0.01])
FISHEYE = {"model": "opencv_fisheye", "width": 800, "height": 800, "fx": 230, "fy": 230,
           "cx": 399.5, "cy": 399.5, "dist_coeffs": [0.02, -0.004, 0.0005, 0], "max_fov_deg": 200}
DOUBLE_SPHERE = {"model": "double_sphere", "width": 752, "height": 480, "fx": 349.7, "fy": 348.9,
                 "cx": 365.8, "cy": 249.9, "xi": -0.2, "alpha": 0.57}

START = (np.array([0.02, -0.01, 0.005]), np.array([0.1, -0.05, 0.2]))
END = (np.array([0.06, 0.04, -0.01]), np.array([-0.2, 0.1, 0.25]))


def camera(name):
    if name == "standard":
        return vklens.Camera(**STANDARD)
    return vklens.Camera.from_dict(FISHEYE if name == "fisheye" else DOUBLE_SPHERE)


def opencv_projector(name, cam):
    """The camera's projection of world points from (rvec, tvec): OpenCV's own where it has
    the model, vklens's global shutter for the double sphere."""
    K = np.array([[cam.fx, 0, cam.cx], [0, cam.fy, cam.cy], [0, 0, 1]])
    D = cam.dist_coeffs

    def project(points, rvec, tvec):
        if name == "standard":
            return cv2.projectPoints(points, rvec, tvec, K, D)[0].reshape(-1, 2)
        if name == "fisheye":
            return cv2.fisheye.projectPoints(points.reshape(-1, 1, 3), rvec, tvec, K, D)[0].reshape(-1, 2)
        return cam.project_points(points, rvec=rvec, tvec=tvec)

    return project


def pose_at(s):
    """rvec, tvec at readout time s: R_wc(s) = R_wc0 exp(s log(R_wc0ᵀ R_wc1)), C linear."""
    r0, t0 = cv2.Rodrigues(START[0])[0], START[1]
    r1, t1 = cv2.Rodrigues(END[0])[0], END[1]
    c0, c1 = -r0.T @ t0, -r1.T @ t1
    log = cv2.Rodrigues(r0 @ r1.T)[0].ravel()  # R_wc0ᵀ R_wc1 = R_cw0 R_cw1ᵀ
    r_wc = r0.T @ cv2.Rodrigues(s * log)[0]
    r_cw = r_wc.T
    c = (1 - s) * c0 + s * c1
    return cv2.Rodrigues(r_cw)[0].ravel(), -r_cw @ c


def line_time(uv, readout, w, h):
    u, v = uv[..., 0], uv[..., 1]
    return {"top_to_bottom": v / (h - 1), "bottom_to_top": 1 - v / (h - 1),
            "left_to_right": u / (w - 1), "right_to_left": 1 - u / (w - 1)}[readout]


def numpy_solve(project, points, readout, w, h, cells=1024):
    """The first self-consistent readout time of every point by a fine scan and bisection
    (the nearer end of the readout where no line reads a point)."""
    s_grid = np.linspace(0, 1, cells + 1)
    uv = np.stack([project(points, *pose_at(s)) for s in s_grid])  # (S, N, 2)
    g = s_grid[:, None] - line_time(uv, readout, w, h)
    out = np.full((len(points), 2), np.nan)
    for i in range(len(points)):
        change = np.nonzero(np.sign(g[:-1, i]) != np.sign(g[1:, i]))[0]
        if len(change) == 0:
            out[i] = uv[0, i] if g[0, i] > 0 else uv[-1, i]
            continue
        lo, hi = s_grid[change[0]], s_grid[change[0] + 1]
        below = g[change[0], i] < 0
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if not lo < mid < hi:
                break
            p = project(points[i:i + 1], *pose_at(mid))
            if (mid - line_time(p, readout, w, h)[0] < 0) == below:
                lo = mid
            else:
                hi = mid
        out[i] = project(points[i:i + 1], *pose_at(0.5 * (lo + hi)))[0]
    return out


def world_points(cam, n, seed):
    """Points seen across the image from START, at 1.5 to 12 m; in front of the image plane
    (OpenCV's fisheye projection stops at 90° off the axis, the 200° lens does not)."""
    rng = np.random.default_rng(seed)
    w, h = cam.size
    uv = np.column_stack([rng.uniform(0, w - 1, n), rng.uniform(0, h - 1, n)])
    rays = cam.unproject_points(uv)
    rays = rays[np.isfinite(rays).all(axis=1) & (rays[:, 2] > 0.3)]
    depth = rng.uniform(1.5, 12.0, len(rays))[:, None]
    r0 = cv2.Rodrigues(START[0])[0]
    return (rays * depth - START[1]) @ r0  # R_cw0ᵀ (d·ray − t0), row by row


@pytest.mark.parametrize("name", ["standard", "fisheye", "double_sphere"])
@pytest.mark.parametrize("readout", READOUTS)
def test_rolling_shutter_matches_a_numpy_bisection(name, readout):
    cam = camera(name)
    points = world_points(cam, 40, 3)
    ours = cam.project_points(points, START[0], START[1], end_rvec=END[0], end_tvec=END[1],
                              rolling_shutter=readout)
    w, h = cam.size
    theirs = numpy_solve(opencv_projector(name, cam), points, readout, w, h)
    assert ours.shape == (len(points), 2)
    seen = np.isfinite(ours).all(axis=1)
    assert seen.sum() >= 0.9 * len(points)
    assert np.max(np.abs(ours[seen] - theirs[seen])) <= 1e-6
    # The motion is real: the first line's pose alone puts the points pixels away.
    first = cam.project_points(points, START[0], START[1])
    assert np.nanmax(np.abs(ours - first)) > 3


@pytest.mark.parametrize("name", ["standard", "fisheye", "double_sphere"])
def test_a_still_camera_is_the_global_shutter_bit_for_bit(name):
    cam = camera(name)
    seen = world_points(cam, 80, 5)
    n = len(seen)
    points = np.vstack([seen, [[0.0, 0.0, -3.0], [40.0, 0.0, 1.0], [np.nan, 0.0, 1.0]]])
    rvec, tvec = START
    global_ = cam.project_points(points, rvec, tvec)
    if name != "double_sphere":
        opencv = opencv_projector(name, cam)(seen, rvec, tvec)
        assert np.max(np.abs(global_[:n] - opencv)) <= 1e-9
    for readout in READOUTS:
        still = cam.project_points(points, rvec, tvec, rolling_shutter=readout)
        same_end = cam.project_points(points, rvec, tvec, end_rvec=rvec.copy(), end_tvec=tvec.copy(),
                                      rolling_shutter=readout)
        assert np.array_equal(still, global_, equal_nan=True)
        assert np.array_equal(same_end, global_, equal_nan=True)
    assert np.isnan(global_[-1]).all()


def test_the_global_shutter_keeps_its_shapes_and_opencvs_pixels():
    cam = camera("standard")
    K = np.array([[1100.0, 0, 959.5], [0, 1090.0, 539.5], [0, 0, 1]])
    points = world_points(cam, 24, 9)
    theirs = cv2.projectPoints(points, START[0], START[1], K, np.array(STANDARD["dist_coeffs"]))[0]
    ours = cam.project_points(points.reshape(-1, 1, 3), START[0].reshape(3, 1), START[1])
    assert ours.shape == (24, 1, 2)
    assert np.max(np.abs(ours - theirs)) <= 1e-9
    rolled = cam.project_points(points.reshape(4, 6, 3), START[0], START[1], end_rvec=END[0],
                                end_tvec=END[1], rolling_shutter="top_to_bottom")
    assert rolled.shape == (4, 6, 2)


def test_points_the_lens_does_not_see_are_nan():
    cam = camera("standard")
    rows = np.array([[0.0, 0.0, -3.0], [np.nan, 0.0, 1.0], [0.0, np.inf, 2.0], [0.1, 0.2, 3.0]])
    uv = cam.project_points(rows, START[0], START[1], end_rvec=END[0], end_tvec=END[1],
                            rolling_shutter="left_to_right")
    assert np.isnan(uv[:3]).all() and np.isfinite(uv[3]).all()


def test_one_step_from_mid_frame_misses_a_fast_pan_by_pixels():
    """A 180°/s pan read across in 30 ms: warps built on a gyroscope's rotations take a
    point's time from where the mid-frame pose puts it, one step; the solve keeps iterating."""
    cam = camera("standard")
    K = np.array([[1100.0, 0, 959.5], [0, 1090.0, 539.5], [0, 0, 1]])
    D = np.array(STANDARD["dist_coeffs"])
    end_r = np.array([0.0, np.radians(180 * 0.03), 0.0])
    points = world_points(cam, 60, 11) @ cv2.Rodrigues(START[0])[0].T + START[1]  # seen from 0
    ours = cam.project_points(points, np.zeros(3), np.zeros(3), end_rvec=end_r, end_tvec=np.zeros(3),
                              rolling_shutter="left_to_right")
    mid = cv2.projectPoints(points, end_r * 0.5, np.zeros(3), K, D)[0].reshape(-1, 2)
    s = mid[:, 0] / (cam.size[0] - 1)
    one_step = np.array([cv2.projectPoints(p[None], end_r * si, np.zeros(3), K, D)[0].ravel()
                         for p, si in zip(points, s)])
    # The solved pixels are self-consistent: their own column's time gives the pose they are at.
    own = np.array([cv2.projectPoints(p[None], end_r * (uv[0] / (cam.size[0] - 1)), np.zeros(3), K, D)[0].ravel()
                    for p, uv in zip(points, ours)])
    inside = (ours[:, 0] >= 0) & (ours[:, 0] <= cam.size[0] - 1)
    assert np.max(np.abs(own[inside] - ours[inside])) <= 1e-6
    assert np.max(np.linalg.norm(one_step[inside] - ours[inside], axis=1)) > 0.5


def test_the_camera_files_readout_is_the_default(tmp_path):
    ncore = tmp_path / "ncore.json"
    ncore.write_text(json.dumps({"camera_model_type": "ftheta", "camera_model_parameters": {
        "resolution": [1920, 1080], "principal_point": [959.3, 541.8],
        "reference_poly": "PIXELDIST_TO_ANGLE",
        "pixeldist_to_angle_poly": [0.0, 1.02e-3, 3.1e-10, -2.4e-13, 0.0, 0.0],
        "angle_to_pixeldist_poly": [0.0, 980.392, -0.2921, 0.2219, -3.3e-4, 1.5e-4],
        "linear_cde": [1.0, 0.0, 0.0], "max_angle": 1.1, "shutter_type": "ROLLING_LEFT_TO_RIGHT"}}))
    cam = vklens.Camera.load(ncore)
    points = np.array([[1.0, 0.5, 5.0], [-2.0, -0.5, 6.0]])
    moving = dict(end_rvec=[0, 0.05, 0], end_tvec=[-0.3, 0, 0])
    default = cam.project_points(points, [0, 0, 0], [0, 0, 0], **moving)
    named = cam.project_points(points, [0, 0, 0], [0, 0, 0], rolling_shutter="left_to_right", **moving)
    other = cam.project_points(points, [0, 0, 0], [0, 0, 0], rolling_shutter="top_to_bottom", **moving)
    assert np.array_equal(default, named) and np.isfinite(default).all()
    assert not np.array_equal(default, other)


def test_bad_arguments_are_refused_by_name():
    cam = camera("standard")
    p = np.array([[0.0, 0.0, 2.0]])
    with pytest.raises(vklens.InputError, match="rolling_shutter") as e:
        cam.project_points(p, end_rvec=[0, 0.1, 0], end_tvec=[0, 0, 0])
    assert e.value.argument == "end_rvec"
    with pytest.raises(vklens.InputError, match="end_tvec"):
        cam.project_points(p, end_rvec=[0, 0.1, 0], rolling_shutter="top_to_bottom")
    with pytest.raises(vklens.InputError, match="top_to_bottom") as e:
        cam.project_points(p, rolling_shutter="diagonal")
    assert e.value.argument == "rolling_shutter"
    with pytest.raises(vklens.InputError, match="end_rvec"):
        cam.project_points(p, end_rvec=[np.nan, 0, 0], end_tvec=[0, 0, 0], rolling_shutter="top_to_bottom")
    # A ValueError too, as Python users expect of bad input.
    with pytest.raises(ValueError):
        cam.project_points(p, rolling_shutter="sideways")


def board_corners(frame, size):
    """OpenCV's chessboard detector on a rendered frame: inner corners refined to sub-pixel."""
    rgba = frame["color"].astype(np.float64)
    alpha = rgba[:, :, 3:4] / 255.0
    grey = (rgba[:, :, :3].mean(axis=2, keepdims=True) * alpha + 128 * (1 - alpha))[:, :, 0]
    grey = grey.astype(np.uint8)
    ok, corners = cv2.findChessboardCorners(grey, size)
    assert ok, "no chessboard found"
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-4)
    return cv2.cornerSubPix(grey, corners, (5, 5), (-1, -1), criteria).reshape(-1, 2)


def corner_errors(found, projected):
    """Each detected corner's distance to the nearest projected board corner (px)."""
    projected = projected[np.isfinite(projected).all(axis=1)]
    d = np.linalg.norm(found[:, None] - projected[None], axis=2)
    return d.min(axis=1)


def test_rendered_board_corners_sit_where_the_solve_puts_them(device):
    """The pan of examples/scenes/rolling_shutter.toml, rendered per vertex (4× supersampled):
    OpenCV's detector finds the board's corners as far from the rolling-shutter projection of
    the board as it finds them from the global shutter's projection in the still twin — the
    detector's own floor — while the first line's pose alone misses them by pixels."""
    base = REPO / "examples" / "scenes"
    tables = tomllib.loads((base / "rolling_shutter.toml").read_text())
    tables["render"] = {"supersample": 4}
    pose = tables["poses"][0]
    rvec, tvec = np.array(pose["rvec"]), np.array(pose["tvec"])
    end = dict(end_rvec=np.array(pose["end_rvec"]), end_tvec=np.array(pose["end_tvec"]),
               rolling_shutter=tables["sensor"]["rolling_shutter"])
    cam = vklens.Camera.load(str(base / tables["optics"]["camera"]))
    # The 12×8 inner corners, wherever the board's origin is: a wider grid of its 10 cm pitch.
    grid = np.array([[x * 0.1, y * 0.1, 0.0] for y in range(-12, 13) for x in range(-14, 15)])

    moving = vklens.render_scene(tables, device=device, base=base)[0]
    rolled = corner_errors(board_corners(moving, (12, 8)), cam.project_points(grid, rvec, tvec, **end))
    first_pose = corner_errors(board_corners(moving, (12, 8)), cam.project_points(grid, rvec, tvec))

    still = dict(tables, poses=[{"rvec": pose["rvec"], "tvec": pose["tvec"]}])
    floor = corner_errors(board_corners(vklens.render_scene(still, device=device, base=base)[0], (12, 8)),
                          cam.project_points(grid, rvec, tvec))
    assert len(rolled) == 96
    assert rolled.mean() <= 1.25 * floor.mean() + 0.02, (rolled.mean(), floor.mean())
    assert rolled.max() <= 1.25 * floor.max() + 0.05, (rolled.max(), floor.max())
    assert first_pose.max() > 5, first_pose.max()
