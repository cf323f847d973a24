"""Labels through the lens from Python: range, classes, boxes, keypoints and the object list of
examples/scenes/ground_truth.toml (a 200° fisheye over the named boxes), checked against the
frame's own ID image and against OpenCV's fisheye projection."""

import json

import numpy as np
import pytest

import vklens
from conftest import REPO

SCENE = REPO / "examples" / "scenes" / "ground_truth.toml"


@pytest.fixture(scope="module")
def frame(device):
    return vklens.render_scene(SCENE, device=device)[0]


def test_every_label_comes_with_the_frame(frame):
    h, w = frame["ids"].shape
    assert frame["range"].shape == (h, w) and frame["range"].dtype == np.float32
    assert frame["classes"].shape == (h, w) and frame["classes"].dtype == np.uint16
    assert [o["name"] for o in frame["objects"]] == ["floor", "box_red", "box_green", "box_blue"]
    # [classes]: "box_red" = 2 comes first, then "box_*" = 1; the floor matches neither.
    assert [o["class"] for o in frame["objects"]] == [0, 2, 1, 1]
    drawn = frame["ids"] > 0
    # Range is the distance along the ray: never less than |z|, +inf where nothing is drawn.
    assert (frame["range"][drawn] >= np.abs(frame["depth"][drawn]) * (1 - 1e-6)).all()
    assert np.isinf(frame["range"][~drawn]).all()


def test_classes_are_the_objects_classes_pixel_by_pixel(frame):
    lut = np.zeros(int(frame["ids"].max()) + 1, np.uint16)
    for o in frame["objects"]:
        lut[o["id"]] = o["class"]
    assert np.array_equal(frame["classes"], lut[frame["ids"]])


def test_visible_boxes_are_the_id_images_tight_boxes(frame):
    ids = frame["ids"]
    assert {b["id"] for b in frame["boxes"]} == set(np.unique(ids[ids > 0]).tolist())
    for b in frame["boxes"]:
        ys, xs = np.nonzero(ids == b["id"])
        assert b["visible_px"] == len(xs)
        assert b["bbox_visible"] == [xs.min(), ys.min(), xs.max() + 1, ys.max() + 1]
        x0, y0, x1, y1 = b["bbox_full"]
        # The whole object holds its visible part (to the budget, 0.05 px).
        assert x0 <= xs.min() + 0.55 and y0 <= ys.min() + 0.55
        assert x1 >= xs.max() + 0.45 and y1 >= ys.max() + 0.45
        assert len(b["corners_3d"]) == 8 and len(b["corners_visible"]) == 8


def test_keypoints_land_where_opencv_projects_them_and_the_hidden_one_is_hidden(frame):
    cv2 = pytest.importorskip("cv2")
    cam = json.loads((REPO / "examples" / "cameras" / "fisheye_200.json").read_text())
    K = np.array([[cam["fx"], 0, cam["cx"]], [0, cam["fy"], cam["cy"]], [0, 0, 1.0]])
    D = np.array(cam["dist_coeffs"], np.float64)
    points = np.array([[-0.9, -0.1, 0.4], [0.0, -0.4, 1.2], [0.9, 0.05, 0.2], [0.0, 0.5, 1.2]])
    rvec, tvec = np.array([1.1, 0.0, 0.0]), np.array([-0.1, 0.4, 0.55])
    want, _ = cv2.fisheye.projectPoints(points.reshape(-1, 1, 3), rvec, tvec, K, D)
    got = np.array([k["pixel"] for k in frame["keypoints"]])
    assert np.abs(got - want.reshape(-1, 2)).max() < 1e-6
    assert [k["visible"] for k in frame["keypoints"]] == [True, True, True, False]


def test_a_dicts_classes_keep_their_order(device):
    import tomllib

    tables = tomllib.loads(SCENE.read_text())
    tables["outputs"] = {"color": False, "classes": True}
    tables["classes"] = {"box_*": 1, "box_red": 2}
    f = vklens.render_scene(tables, device=device, base=SCENE.parent)[0]
    # "box_*" now comes first and wins for the red box too.
    assert [o["class"] for o in f["objects"]] == [0, 1, 1, 1]
    assert set(np.unique(f["classes"]).tolist()) == {0, 1}
    # Neither the ID image nor a range was asked for: only what was.
    assert "ids" not in f and "range" not in f and "classes" in f


def test_a_class_that_is_not_a_whole_number_names_its_key(device):
    import tomllib

    tables = tomllib.loads(SCENE.read_text())
    tables["classes"] = {"box_*": "car"}
    with pytest.raises(vklens.InputError, match=r"\[classes\] \"box_\*\""):
        vklens.render_scene(tables, device=device, base=SCENE.parent)
