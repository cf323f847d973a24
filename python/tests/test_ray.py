"""examples/python/batch_ray.py on a local Ray instance: 2 workers, 20 small frames, every
output equal to the single-process result."""

import os
import subprocess
import sys

import cv2
import numpy as np

import vklens
from conftest import REPO

EXAMPLE = REPO / "examples" / "python" / "batch_ray.py"


def test_batch_ray_equals_one_process(tmp_path):
    cam = vklens.Camera(width=96, height=64, fx=60, fy=60, cx=47.5, cy=31.5, dist_coeffs=[-0.25, 0.06, 0.001, 0.0])
    cam.save(tmp_path / "cam.json")
    frames = tmp_path / "frames"
    frames.mkdir()
    rng = np.random.default_rng(11)
    images = {}
    for i in range(20):
        img = rng.integers(0, 256, (64, 96, 3), dtype=np.uint8)
        cv2.imwrite(str(frames / f"f{i:02}.png"), img)
        images[f"f{i:02}.png"] = img
    out = tmp_path / "lens"
    env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0")
    run = subprocess.run(
        [sys.executable, EXAMPLE, "--camera", tmp_path / "cam.json", "--input", frames, "--output", out,
         "--workers", "2"],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    assert "warped 20 frame(s)" in run.stdout
    warper = vklens.Warper(cam)
    for name, img in images.items():
        got = cv2.imread(str(out / name), cv2.IMREAD_UNCHANGED)
        assert got is not None, name
        assert np.array_equal(got, warper(img)), name
    assert sorted(p.name for p in out.iterdir()) == sorted(images)  # no temporary files left
    # a second run skips what is done
    again = subprocess.run(
        [sys.executable, EXAMPLE, "--camera", tmp_path / "cam.json", "--input", frames, "--output", out,
         "--workers", "2"],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert again.returncode == 0 and "warped 0 frame(s) (20 skipped)" in again.stdout, again.stderr[-2000:]
