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
    assert set(frames[0]) == {"index", "ms", "ids", "depth"}
    for a, b in zip(frames, from_file):
        assert (a["ids"] == b["ids"]).all()
        assert np.array_equal(a["depth"], b["depth"])


def test_render_scene_bad_input():
    with pytest.raises(vklens.InputError, match="scene"):
        vklens.render_scene(42)
    with pytest.raises(vklens.Error):
        vklens.render_scene({"geometry": {"scene": "no-such-scene"}})
