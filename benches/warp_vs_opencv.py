#!/usr/bin/env python3
"""vklens's warp beside OpenCV on the same machine, in the same run.

Runs `vklens bench warp --json`, then at the same sizes times
  * cv2.remap with precomputed CV_32FC1 maps, INTER_LINEAR, RGBA8 (the engine-style LUT warp),
  * cv2.undistortPoints over every pixel (OpenCV's default 5 iterations; all 14 coefficients),
and prints each vklens row's ratio to them and to the copy pass (the driver's floor).

Usage: benches/warp_vs_opencv.py [path/to/vklens] [--size WxH]   (default: target/release/vklens)
"""
import json
import subprocess
import sys
import time

import cv2
import numpy as np

args = [a for a in sys.argv[1:] if not a.startswith("--") and "x" not in a]
vklens = args[0] if args else "target/release/vklens"
size_args = [a for a in sys.argv[1:] if a.startswith("--size") or ("x" in a and a[0].isdigit())]
cmd = [vklens, "bench", "warp", "--json"] + (["--size", size_args[-1].split("=")[-1]] if size_args else [])
print("running", " ".join(cmd), file=sys.stderr)
rows = [json.loads(l) for l in subprocess.run(cmd, check=True, capture_output=True, text=True).stdout.splitlines() if l.strip()]


def bench_camera(w, h):
    """vklens::internal::bench::warp::bench_camera: the shared prism_tilt case scaled to the size."""
    s = w / 1024.0
    K = np.array([[800 * s, 0, (w - 1) / 2], [0, 790 * s, (h - 1) / 2], [0, 0, 1]])
    D = np.array([-0.12, 0.04, 0.002, -0.001, 0, 0, 0, 0, 0.003, -0.0005, -0.002, 0.0004, 0.01, -0.015])
    return K, D


def median_ms(f, repeats=5):
    f()
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        f()
        times.append((time.perf_counter() - t) * 1e3)
    return sorted(times)[len(times) // 2]


peers = {}
for w, h in sorted({(r["width"], r["height"]) for r in rows}):
    K, D = bench_camera(w, h)
    img = np.random.default_rng(0).integers(0, 255, (h, w, 4), dtype=np.uint8)
    mx, my = cv2.initUndistortRectifyMap(K, D, None, K, (w, h), cv2.CV_32FC1)
    remap = median_ms(lambda: cv2.remap(img, mx, my, cv2.INTER_LINEAR))
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    pts = np.stack([xs.ravel(), ys.ravel()], axis=1).reshape(-1, 1, 2)
    undist = median_ms(lambda: cv2.undistortPoints(pts, K, D), repeats=3)
    peers[(w, h)] = (remap, undist)

print(f"OpenCV {cv2.__version__}, {cv2.getNumThreads()} threads; vklens on lavapipe or whatever VKLENS_DEVICE picked\n")
print("| size | vklens pass | ms | × copy | × cv2.remap | cv2.remap ms | cv2.undistortPoints ms | undistortPoints ÷ vklens |")
print("|---|---|---:|---:|---:|---:|---:|---:|")
for r in rows:
    w, h = r["width"], r["height"]
    remap, undist = peers[(w, h)]
    copy = next(x["frame_ms"] for x in rows if x["bench"] == "copy" and x["width"] == w and x["height"] == h)
    if r["bench"] == "copy":
        name, ms = "copy (floor)", r["frame_ms"]
    elif r["bench"] == "inverse_map":
        name, ms = f"inverse map build: {r['method']}", r["ms"]
    else:
        name, ms = f"warp {r['method']}{' chromatic' if r['chromatic'] else ''}", r["frame_ms"]
    print(f"| {w}×{h} | {name} | {ms:.1f} | {ms / copy:.2f} | {ms / remap:.1f} | {remap:.1f} | {undist:.0f} | {undist / ms:.2f} |")
