#!/usr/bin/env python3
"""Cross-checks vklens against OpenCV itself (opencv-python-headless), run by tests/opencv.rs.

(a) `vklens undistort` equals cv2.initUndistortRectifyMap + cv2.remap (INTER_LINEAR) to within
    interpolation rounding: OpenCV quantizes map coordinates to 1/32 px (INTER_BITS = 5) and
    weights to 15 bits, so on a smooth image the two agree to a grey level (bound: mean 0.05,
    max 1 level; measured: max 1 level on every camera).
(b) `vklens distort` followed by OpenCV's undistortion returns the pinhole image (Lambers et al.'s
    Fig. 2 round trip), with a stated PSNR inside the valid region (bound 40 dB; measured
    42.8-43.9 dB: two bilinear resamplings of an 8-bit image).

Usage: opencv_crosscheck.py VKLENS_BINARY SHARED_DIR
"""
import json
import os
import subprocess
import sys
import tempfile

import cv2
import numpy as np

vklens, shared = sys.argv[1], sys.argv[2]
cases = {c["name"]: c for c in json.load(open(os.path.join(shared, "reference", "opencv_standard_model.json")))["cases"]}
tmp = tempfile.mkdtemp(prefix="vklens-opencv-")
failures = []


def smooth_image(w, h):
    """Sinusoids with periods of 30-60 px: gradients of at most ~16 grey levels per pixel, so
    OpenCV's 1/32 px coordinate quantization moves values by well under a level."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    b = 128 + 100 * np.sin(x / 9.0) * np.cos(y / 11.0)
    g = 128 + 100 * np.sin((x + y) / 13.0)
    r = 128 + 100 * np.cos(x / 7.0 - y / 17.0)
    return np.clip(np.dstack([b, g, r]), 0, 255).round().astype(np.uint8)


def run(*args):
    subprocess.run([vklens, *args], check=True, stderr=subprocess.DEVNULL)


def camera(name):
    c = cases[name]
    K = np.array([[c["fx"], 0, c["cx"]], [0, c["fy"], c["cy"]], [0, 0, 1]], dtype=np.float64)
    D = np.array(c["dist_coeffs"], dtype=np.float64)
    path = os.path.join(tmp, f"{name}.json")
    json.dump({k: c[k] for k in ("width", "height", "fx", "fy", "cx", "cy", "dist_coeffs")}, open(path, "w"))
    return c["width"], c["height"], K, D, path


def psnr(a, b):
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(255.0**2 / mse)


print("(a) vklens undistort vs cv2.initUndistortRectifyMap + cv2.remap")
for name in ["seed_fig2", "seed_fig1_barrel", "webcam_plumb_bob", "prism_tilt", "rational_wide", "strong_pincushion"]:
    w, h, K, D, cam = camera(name)
    photo = smooth_image(w, h)
    src, out, mask = (os.path.join(tmp, f"{name}_{s}.png") for s in ("photo", "vk", "mask"))
    cv2.imwrite(src, photo)
    run("undistort", "--camera", cam, "--input", src, "--output", out, "--mask", mask)
    ours = cv2.imread(out)[..., :3]
    valid = cv2.imread(mask, cv2.IMREAD_GRAYSCALE) > 127
    mx, my = cv2.initUndistortRectifyMap(K, D, None, K, (w, h), cv2.CV_32FC1)
    theirs = cv2.remap(photo, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    # Compare where vklens has a source at least one pixel inside the photo's frame (at the
    # very edge OpenCV blends with its border value, vklens clamps to the edge pixel).
    inner = valid & (mx >= 0.5) & (my >= 0.5) & (mx <= w - 1.5) & (my <= h - 1.5)
    d = np.abs(ours.astype(int) - theirs.astype(int))[inner]
    mean, worst = d.mean(), d.max()
    print(f"  {name}: {inner.sum()} px compared, mean {mean:.5f}, max {worst} grey levels")
    if mean > 0.05 or worst > 1:
        failures.append(f"(a) {name}: mean {mean:.5f} / max {worst} levels exceed 0.05 / 1")

print("(b) vklens distort, then OpenCV undistortion: Lambers et al.'s Fig. 2 round trip")
for name, bound in [("seed_fig2", 40.0), ("seed_fig1_barrel", 40.0), ("webcam_plumb_bob", 40.0)]:
    w, h, K, D, cam = camera(name)
    pinhole = smooth_image(w, h)
    src, out, mask = (os.path.join(tmp, f"{name}_{s}.png") for s in ("pinhole", "distorted", "dmask"))
    cv2.imwrite(src, pinhole)
    run("distort", "--camera", cam, "--input", src, "--output", out, "--mask", mask)
    distorted = cv2.imread(out)[..., :3]
    valid = (cv2.imread(mask, cv2.IMREAD_GRAYSCALE) > 127).astype(np.uint8) * 255
    mx, my = cv2.initUndistortRectifyMap(K, D, None, K, (w, h), cv2.CV_32FC1)
    back = cv2.remap(distorted, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    back_valid = cv2.remap(valid, mx, my, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT) > 0
    # Inside the region whose light passed through the valid, filled part of the lens image,
    # one pixel away from its edge (there the remap blends with fill).
    region = cv2.erode(back_valid.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    p = psnr(back[region], pinhole[region])
    print(f"  {name}: PSNR {p:.1f} dB over {region.sum()} px (bound {bound} dB)")
    if p < bound:
        failures.append(f"(b) {name}: PSNR {p:.1f} dB < {bound} dB")

if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("all OpenCV cross-checks passed")
