#!/usr/bin/env python3
"""vklens's warp beside OpenCV on the same machine, in the same run.

Runs `vklens bench warp --json`, then at the same sizes times
  * cv2.remap with precomputed CV_32FC1 maps, INTER_LINEAR, RGBA8 (the engine-style LUT warp),
  * cv2.undistortPoints over every pixel (OpenCV's default 5 iterations; all 14 coefficients),
and prints each vklens row's ratio to them and to the copy pass (the driver's floor).

Usage:
  cli/benches/warp_vs_opencv.py [path/to/vklens] [--size WxH]   (default: target/release/vklens)
  cli/benches/warp_vs_opencv.py --json                           vklens's rows, then OpenCV's, as JSON lines
  cli/benches/warp_vs_opencv.py --opencv-only --sizes 800x600,1920x1080 --json
                                                             OpenCV's rows only (what `vklens bench all` runs)
"""
import argparse
import json
import subprocess
import sys
import time

import cv2
import numpy as np


def bench_camera(w, h):
    """vklens's bench::warp::bench_camera: the shared prism_tilt case scaled to the size."""
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


def opencv_row(w, h):
    """OpenCV's times at one size, as a row beside `vklens bench warp`'s (kind `opencv`)."""
    K, D = bench_camera(w, h)
    img = np.random.default_rng(0).integers(0, 255, (h, w, 4), dtype=np.uint8)
    mx, my = cv2.initUndistortRectifyMap(K, D, None, K, (w, h), cv2.CV_32FC1)
    remap = median_ms(lambda: cv2.remap(img, mx, my, cv2.INTER_LINEAR))
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    pts = np.stack([xs.ravel(), ys.ravel()], axis=1).reshape(-1, 1, 2)
    undist = median_ms(lambda: cv2.undistortPoints(pts, K, D), repeats=3)
    return {"bench": "warp", "kind": "opencv", "width": w, "height": h, "remap_ms": remap,
            "undistort_points_ms": undist, "opencv": cv2.__version__, "threads": cv2.getNumThreads()}


def parse_size(s):
    try:
        w, h = (int(v) for v in s.lower().replace("×", "x").split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"`{s}` is not WxH")
    return w, h


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("vklens", nargs="?", default="target/release/vklens", help="the vklens binary")
    p.add_argument("--size", type=parse_size, help="measure only this size (WxH)")
    p.add_argument("--sizes", help="comma-separated WxH for --opencv-only (default: vklens's three)")
    p.add_argument("--json", action="store_true", help="one JSON object per line instead of a table")
    p.add_argument("--opencv-only", action="store_true",
                   help="time OpenCV only, at --sizes, without running vklens")
    args = p.parse_args(argv)

    if args.opencv_only:
        if args.sizes:
            sizes = [parse_size(s) for s in args.sizes.split(",")]
        else:
            sizes = [args.size] if args.size else [(800, 600), (1920, 1080), (3840, 2160)]
        rows = []
    else:
        cmd = [args.vklens, "bench", "warp", "--json"]
        if args.size:
            cmd += ["--size", f"{args.size[0]}x{args.size[1]}"]
        print("running", " ".join(cmd), file=sys.stderr)
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        rows = [json.loads(line) for line in out.splitlines() if line.strip()]
        sizes = sorted({(r["width"], r["height"]) for r in rows})

    peers = {}
    for w, h in sizes:
        print(f"OpenCV at {w}x{h} ...", file=sys.stderr, flush=True)
        peers[(w, h)] = opencv_row(w, h)
    if args.json:
        for r in rows + list(peers.values()):
            print(json.dumps(r))
        return
    if args.opencv_only:
        print("| size | cv2.remap ms | cv2.undistortPoints ms |\n|---|---:|---:|")
        for (w, h), r in peers.items():
            print(f"| {w}×{h} | {r['remap_ms']:.2f} | {r['undistort_points_ms']:.0f} |")
        return

    print(f"OpenCV {cv2.__version__}, {cv2.getNumThreads()} threads; vklens on the device VKLENS_DEVICE picked\n")
    print("| size | vklens pass | ms | × copy | × cv2.remap | cv2.remap ms | cv2.undistortPoints ms | undistortPoints ÷ vklens |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        w, h = r["width"], r["height"]
        remap, undist = peers[(w, h)]["remap_ms"], peers[(w, h)]["undistort_points_ms"]
        copy = next(x["frame_ms"] for x in rows if x["kind"] == "copy" and x["width"] == w and x["height"] == h)
        if r["kind"] == "copy":
            name, ms = "copy (floor)", r["frame_ms"]
        elif r["kind"] == "inverse_map":
            name, ms = f"inverse map build: {r['method']}", r["ms"]
        else:
            name, ms = f"warp {r['method']}{' chromatic' if r['chromatic'] else ''}", r["frame_ms"]
        print(f"| {w}×{h} | {name} | {ms:.1f} | {ms / copy:.2f} | {ms / remap:.1f} | {remap:.1f} | {undist:.0f} | {undist / ms:.2f} |")


if __name__ == "__main__":
    main()
