"""Scenes through the lens from Python: a scene file or the same tables as a dict."""

import numpy as np
import pytest

import vklens
from conftest import REPO

SCENE = REPO / "examples" / "scenes" / "ids_and_flow.toml"


def test_render_scene_file_gives_the_outputs_it_asks(device):
    frames = vklens.render_scene(SCENE, device=device)
    assert len(frames) == 3
    f = frames[1]
    h, w = f["ids"].shape
    assert f["color"].shape == (h, w, 4) and f["color"].dtype == np.uint8
    assert f["ids"].dtype == np.uint32 and len(np.unique(f["ids"])) > 2
    assert f["flow"].shape == (h, w, 2) and f["flow"].dtype == np.float32
    assert f["depth"].shape == (h, w) and f["depth"].dtype == np.float32
    drawn = f["ids"] > 0
    assert np.isfinite(f["depth"][drawn]).all() and np.isinf(f["depth"][~drawn]).all()
    assert np.isfinite(f["flow"][drawn]).mean() > 0.9


def test_render_scene_dict_equals_the_file(device):
    import tomllib

    tables = tomllib.loads(SCENE.read_text())
    tables["outputs"] = {"color": False, "ids": True, "depth": True}
    frames = vklens.render_scene(tables, device=device, base=SCENE.parent)
    from_file = vklens.render_scene(SCENE, device=device)
    assert set(frames[0]) == {"index", "ms", "ids", "depth", "objects"}
    for a, b in zip(frames, from_file):
        assert (a["ids"] == b["ids"]).all()
        assert np.array_equal(a["depth"], b["depth"])


def test_render_scene_bad_input():
    with pytest.raises(vklens.InputError, match="scene"):
        vklens.render_scene(42)
    with pytest.raises(vklens.Error):
        vklens.render_scene({"geometry": {"scene": "no-such-scene"}})


def test_jittered_scene_corners_sit_where_opencv_projects_them(device, tmp_path):
    """The corners of a supersampled, jittered scene render against cv2.projectPoints: the
    mean offset is the detector's floor (a jittered pass once drew with the previous pass's
    projection, which moved the whole image by the last offset, 0.3 px here)."""
    cv2 = pytest.importorskip("cv2")
    cam = {"width": 800, "height": 600, "fx": 700.0, "fy": 700.0, "cx": 399.5, "cy": 299.5,
           "dist_coeffs": [-0.2, 0.05, 0.001, -0.0005]}
    (tmp_path / "cam.json").write_text(__import__("json").dumps(cam))
    rvec, tvec = [0.25, -0.35, 0.08], [-0.17, -0.09, 0.50]
    K = np.array([[700.0, 0, 399.5], [0, 700.0, 299.5], [0, 0, 1]])
    for s, j in ((1, 4), (2, 4)):
        frames = vklens.render_scene({
            "geometry": {"scene": "checkerboard:9x6:0.04"}, "optics": {"camera": "cam.json"},
            "render": {"supersample": s, "jitter": j}, "poses": [{"rvec": rvec, "tvec": tvec}],
        }, device=device, base=tmp_path)
        rgba = frames[0]["color"].astype(np.float64)
        a = rgba[:, :, 3:4] / 255.0
        grey = (rgba[:, :, :3].mean(axis=2, keepdims=True) * a + 128 * (1 - a))[:, :, 0].astype(np.uint8)
        ok, corners = cv2.findChessboardCorners(grey, (9, 6))
        assert ok, f"supersample {s}, jitter {j}: no corners found"
        corners = cv2.cornerSubPix(grey, corners, (5, 5), (-1, -1),
                                   (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-4)).reshape(-1, 2)
        # The board's inner corners, wherever vklens puts its origin: the nearest projection
        # of a grid wide enough to hold every placement.
        grid = np.array([[x * 0.04, y * 0.04, 0.0] for y in range(-8, 9) for x in range(-10, 11)])
        proj, _ = cv2.projectPoints(grid, np.array(rvec), np.array(tvec), K, np.array(cam["dist_coeffs"]))
        proj = proj.reshape(-1, 2)
        nearest = proj[np.linalg.norm(corners[:, None] - proj[None], axis=2).argmin(axis=1)]
        offset = (corners - nearest).mean(axis=0)
        assert np.abs(offset).max() < 0.05, f"supersample {s}, jitter {j}: corners off by {offset} px"


def test_render_scene_pans_through_a_rolling_shutter(device):
    """A scene dict whose pose moves during the readout renders per vertex: the first line is
    read from the pose, so the top rows are the still frame's, and the lower ones are not."""
    base = REPO / "examples" / "scenes"
    pose = {"rvec": [0.0, 0.0, 0.0], "tvec": [0.0, 0.0, 2.0]}
    tables = {
        "geometry": {"scene": "grid:8"}, "optics": {"camera": "../cameras/barrel_k1k2.json"},
        "outputs": {"color": False, "ids": True, "depth": True},
        "sensor": {"rolling_shutter": "top_to_bottom"}, "poses": [pose],
    }
    still = vklens.render_scene(tables, device=device, base=base)[0]
    tables["poses"] = [dict(pose, end_rvec=[0.0, 0.1, 0.0], end_tvec=[0.05, 0.0, 2.0])]
    moving = vklens.render_scene(tables, device=device, base=base)[0]
    assert (moving["ids"][0] != still["ids"][0]).sum() < 5
    changed = (moving["ids"] != still["ids"]).mean()
    assert changed > 0.02, changed
    drawn = moving["ids"] > 0
    assert np.isfinite(moving["depth"][drawn]).all()
    # Without a rolling shutter the end pose contradicts the global one.
    del tables["sensor"]
    with pytest.raises(vklens.Error, match="end_rvec"):
        vklens.render_scene(tables, device=device, base=base)
