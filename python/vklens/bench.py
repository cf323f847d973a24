"""Frames per second of vklens's Warper against OpenCV in the same process, same run.

    python -m vklens.bench                 # 800x600 and 1920x1080, RGB uint8
    python -m vklens.bench --frames 50 --json

For each size and direction it times, in this process:

* vklens: the device's start-up (once per process), ``Warper(...)`` plus its first frame
  (pipelines, maps: the first-frame latency), then a loop of frames into a caller-owned ``out=`` array;
* OpenCV, the way a user writes it: for undistort ``cv2.initUndistortRectifyMap`` then a
  ``cv2.remap`` loop; for distort (OpenCV has no distort warp) ``cv2.undistortPoints`` over
  every output pixel once to build the maps, then the same ``cv2.remap`` loop.

The ratio is vklens's frames per second over OpenCV's (above 1: vklens is faster). On
lavapipe, a CPU Vulkan driver, the loop is expected to trail ``cv2.remap``'s hand-written SIMD;
on a GPU the upload and readback dominate.
"""

import argparse
import json
import statistics
import sys
import time

import numpy as np

import vklens


def camera(width, height):
    """Lambers et al.'s Fig. 2 lens, scaled to the size."""
    f = 0.5 * width
    return vklens.Camera(width=width, height=height, fx=f, fy=f, cx=(width - 1) / 2, cy=(height - 1) / 2,
                         dist_coeffs=[-0.05, 0.01, 0.003, -0.001, 0.0])


def frames_per_second(step, frames, repeats):
    """Median over `repeats` of `frames` calls, as frames per second."""
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(frames):
            step()
        runs.append(frames / (time.perf_counter() - start))
    return statistics.median(runs)


def opencv_maps(cv2, cam, direction):
    K, D = cam.K, cam.dist_coeffs
    size = cam.size
    if direction == "undistort":
        return cv2.initUndistortRectifyMap(K, D, None, K, size, cv2.CV_32FC1)
    v, u = np.mgrid[0:cam.height, 0:cam.width].astype(np.float64)
    pix = np.stack([u.ravel(), v.ravel()], axis=1).reshape(-1, 1, 2)
    xy = cv2.undistortPoints(pix, K, D).reshape(cam.height, cam.width, 2)
    return ((xy[..., 0] * cam.fx + cam.cx).astype(np.float32), (xy[..., 1] * cam.fy + cam.cy).astype(np.float32))


def bench_one(cv2, device, width, height, direction, frames, repeats):
    cam = camera(width, height)
    rng = np.random.default_rng(1)
    image = rng.integers(0, 256, (height, width, 3), dtype=np.uint8)
    row = {"size": f"{width}x{height}", "direction": direction}

    start = time.perf_counter()
    warper = vklens.Warper(cam, direction=direction, device=device)
    out = warper(image)
    row["vklens_first_frame_ms"] = (time.perf_counter() - start) * 1e3
    row["vklens_fps"] = frames_per_second(lambda: warper(image, out=out), frames, repeats)

    start = time.perf_counter()
    mx, my = opencv_maps(cv2, cam, direction)
    dst = cv2.remap(image, mx, my, cv2.INTER_LINEAR)
    row["opencv_first_frame_ms"] = (time.perf_counter() - start) * 1e3
    row["opencv_fps"] = frames_per_second(lambda: cv2.remap(image, mx, my, cv2.INTER_LINEAR, dst=dst), frames, repeats)
    row["fps_ratio"] = row["vklens_fps"] / row["opencv_fps"]
    row["first_frame_ratio"] = row["opencv_first_frame_ms"] / row["vklens_first_frame_ms"]
    return row


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m vklens.bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--frames", type=int, default=20, help="frames per timed loop (default 20)")
    p.add_argument("--repeats", type=int, default=5, help="timed loops per figure; the median is reported (default 5)")
    p.add_argument("--sizes", default="800x600,1920x1080", help="comma-separated WxH (default 800x600,1920x1080)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    args = p.parse_args(argv)
    try:
        import cv2
    except ImportError:
        p.error("OpenCV is the peer: pip install opencv-python-headless")
    sizes = []
    for s in args.sizes.split(","):
        try:
            w, h = (int(v) for v in s.lower().split("x"))
        except ValueError:
            p.error(f"--sizes: `{s}` is not WxH")
        sizes.append((w, h))
    # OpenCV loads lazily on its first call: pay that before timing its first frame.
    tiny = np.zeros((8, 8), np.float32)
    cv2.remap(np.zeros((8, 8), np.uint8), tiny, tiny, cv2.INTER_LINEAR)
    cv2.initUndistortRectifyMap(np.eye(3), np.zeros(5), None, np.eye(3), (8, 8), cv2.CV_32FC1)
    start = time.perf_counter()
    device = vklens.Device()
    device_ms = (time.perf_counter() - start) * 1e3
    rows = []
    for w, h in sizes:
        for direction in ("undistort", "distort"):
            print(f"{w}x{h} {direction} ...", file=sys.stderr, flush=True)
            rows.append(bench_one(cv2, device, w, h, direction, args.frames, args.repeats))
    meta = {"device": device.name, "opencv": cv2.__version__, "numpy": np.__version__,
            "vklens": vklens.__version__, "device_start_ms": device_ms, "frames": args.frames, "repeats": args.repeats,
            "date": time.strftime("%Y-%m-%d")}
    if args.json:
        print(json.dumps({"meta": meta, "rows": rows}, indent=1))
        return
    print(f"device: {meta['device']} (start-up {device_ms:.0f} ms, once per process); OpenCV {meta['opencv']}; "
          f"{meta['date']}; median of {args.repeats} x {args.frames} frames")
    print("| size | direction | vklens fps | cv2.remap fps | × cv2 | vklens first frame | OpenCV first frame (maps + remap) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['size']} | {r['direction']} | {r['vklens_fps']:.1f} | {r['opencv_fps']:.1f} | "
              f"{r['fps_ratio']:.2f}× | {r['vklens_first_frame_ms']:.0f} ms | {r['opencv_first_frame_ms']:.0f} ms |")


if __name__ == "__main__":
    main()
