#!/usr/bin/env python3
"""Cross-checks vklens against OpenCV itself (opencv-python-headless), run by tests/opencv.rs.

(a) `vklens undistort` equals cv2.initUndistortRectifyMap + cv2.remap (INTER_LINEAR) to within
    interpolation rounding: OpenCV quantizes map coordinates to 1/32 px (INTER_BITS = 5) and
    weights to 15 bits, so on a smooth image the two agree to a grey level (bound: mean 0.05,
    max 1 level; measured: max 1 level on every camera).
(b) `vklens distort` followed by OpenCV's undistortion returns the pinhole image (Lambers et al.'s
    Fig. 2 round trip), with a stated PSNR inside the valid region (bound 40 dB; measured
    42.8-43.9 dB: two bilinear resamplings of an 8-bit image).
(d) A ROS stereo camera_info pair (R, P from cv2.stereoRectify and cv2.fisheye.stereoRectify):
    `vklens undistort` rectifies as image_proc does, equal to initUndistortRectifyMap(K, D, R, P)
    + remap within a grey level on both backends; --no-rectification uses K alone.
(c) On fisheye cameras: `vklens undistort` equals cv2.fisheye.initUndistortRectifyMap + cv2.remap
    to within a grey level (bounds as (a)); `vklens points undistort` equals
    cv2.fisheye.undistortPoints run with tight criteria (1e-6 px); `vklens points distort` of
    camera-frame points equals cv2.fisheye.projectPoints (1e-9 px) on a fifth camera made here.
    OpenCV's fisheye undistortPoints and initUndistortRectifyMap take no skew (projectPoints
    takes α as an argument): for the skew camera vklens is compared with maps and points made
    from cv2.fisheye.projectPoints with α itself, and OpenCV's own inverse is shown to miss
    (its reprojection error is printed).

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

print("(c) fisheye: undistort vs cv2.fisheye.initUndistortRectifyMap + remap; points vs cv2.fisheye")
fish_dir = os.path.join(shared, "reference", "fisheye")


def fisheye(name):
    c = json.load(open(os.path.join(fish_dir, f"{name}.json")))
    K = np.array([[c["fx"], 0, c["cx"]], [0, c["fy"], c["cy"]], [0, 0, 1]], dtype=np.float64)
    D = np.array(c["dist_coeffs"], dtype=np.float64)
    return c["width"], c["height"], K, D, c.get("alpha", 0.0), os.path.join(fish_dir, f"{name}.json")


def points_cli(cam, mode, rows, *extra):
    out = subprocess.run([vklens, "points", mode, "--camera", cam, *extra], input=json.dumps(rows),
                         capture_output=True, text=True, check=True).stdout
    return json.loads(out)


for name in ["fish_wide160", "fish_equidistant185", "fish_skew170"]:
    w, h, K, D, alpha, cam = fisheye(name)
    photo = smooth_image(w, h)
    src, out, mask = (os.path.join(tmp, f"{name}_{s}.png") for s in ("photo", "vk", "mask"))
    cv2.imwrite(src, photo)
    run("undistort", "--camera", cam, "--input", src, "--output", out, "--mask", mask)
    ours = cv2.imread(out)[..., :3]
    valid = cv2.imread(mask, cv2.IMREAD_GRAYSCALE) > 127
    # cv2.fisheye.projectPoints takes α as an argument; its undistortPoints and
    # initUndistortRectifyMap have none (they drop the skew).
    skew = alpha != 0
    if skew:
        # The map initUndistortRectifyMap would be if it applied α: projectPoints of the rays
        # of the pinhole output (vklens's: the camera's fx fy cx cy, no skew).
        v, u = np.mgrid[0:h, 0:w].astype(np.float64)
        rays = np.dstack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones_like(u)])
        m, _ = cv2.fisheye.projectPoints(rays.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, D, alpha=alpha)
        mx, my = (m.reshape(h, w, 2)[..., i].astype(np.float32) for i in (0, 1))
    else:
        mx, my = cv2.fisheye.initUndistortRectifyMap(K, D, np.eye(3), K, (w, h), cv2.CV_32FC1)
    theirs = cv2.remap(photo, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    inner = valid & (mx >= 0.5) & (my >= 0.5) & (mx <= w - 1.5) & (my <= h - 1.5)
    d = np.abs(ours.astype(int) - theirs.astype(int))[inner]
    mean, worst = d.mean(), d.max()
    print(f"  {name} undistort: {inner.sum()} px compared, mean {mean:.5f}, max {worst} grey levels")
    if inner.sum() < 1000 or mean > 0.05 or worst > 1:
        failures.append(f"(c) {name}: mean {mean:.5f} / max {worst} levels exceed 0.05 / 1")
    pts = json.load(open(os.path.join(fish_dir, f"{name}.points.json")))["inside"]
    pixels = np.array(pts["pixel"], dtype=np.float64)
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
    cv = cv2.fisheye.undistortPoints(pixels.reshape(-1, 1, 2), K, D, criteria=crit).reshape(-1, 2)
    vk = np.array(points_cli(cam, "undistort", pixels.tolist()), dtype=np.float64)

    def reprojection(x):
        rays = np.hstack([x, np.ones((len(x), 1))]).reshape(-1, 1, 3)
        back, _ = cv2.fisheye.projectPoints(rays, np.zeros(3), np.zeros(3), K, D, alpha=alpha)
        return np.linalg.norm(back.reshape(-1, 2) - pixels, axis=1).max()

    if skew:
        err = reprojection(vk)
        print(f"  {name} undistortPoints: {len(vk)} points, vklens reprojects through cv2.fisheye.projectPoints to {err:.2e} px; OpenCV's own inverse (α dropped) to {reprojection(cv):.2e} px")
    else:
        # In pixels of angle (θ moves a pixel by about f per radian): the normalized
        # difference over 1 + r² (d atan r / dr), times f.
        err = (np.linalg.norm(vk - cv, axis=1) / (1 + np.sum(vk**2, axis=1)) * K[0, 0]).max()
        print(f"  {name} undistortPoints: {len(vk)} points, worst {err:.2e} px from cv2.fisheye")
    if not err <= 1e-6:
        failures.append(f"(c) {name}: undistortPoints differs by {err:.2e} px")

# A fifth fisheye, made here: cv2.fisheye.projectPoints on points below 85°.
rng = np.random.default_rng(5)
K5 = np.array([[612.3, 0, 640.2], [0, 611.8, 479.6], [0, 0, 1]])
D5 = np.array([0.041, -0.013, 0.0021, -0.00033])
five = os.path.join(tmp, "fish_fifth.json")
json.dump({"model": "opencv_fisheye", "width": 1280, "height": 960, "fx": K5[0, 0], "fy": K5[1, 1],
           "cx": K5[0, 2], "cy": K5[1, 2], "dist_coeffs": D5.tolist()}, open(five, "w"))
theta = np.radians(rng.uniform(0, 85, 400))
phi = rng.uniform(0, 2 * np.pi, 400)
dist = rng.uniform(0.5, 30, 400)
xyz = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], 1) * dist[:, None]
cv, _ = cv2.fisheye.projectPoints(xyz.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K5, D5)
vk = np.array(points_cli(five, "distort", xyz.tolist()), dtype=np.float64)
err = np.linalg.norm(vk - cv.reshape(-1, 2), axis=1).max()
print(f"  fish_fifth projectPoints: {len(vk)} points, worst {err:.2e} px from cv2.fisheye")
if not err <= 1e-9:
    failures.append(f"(c) fifth camera: projectPoints differs by {err:.2e} px")

print("(d) a ROS stereo camera_info (R, P) vs cv2.initUndistortRectifyMap(K, D, R, P) + remap, as image_proc")


def camera_info(path, w, h, K, D, R, P, model):
    f = lambda a: "[" + ", ".join(repr(float(x)) for x in np.asarray(a).ravel()) + "]"
    open(path, "w").write(
        f"image_width: {w}\nimage_height: {h}\ncamera_name: {os.path.basename(path)}\n"
        f"camera_matrix:\n  rows: 3\n  cols: 3\n  data: {f(K)}\n"
        f"distortion_model: {model}\ndistortion_coefficients:\n  rows: 1\n  cols: {len(D)}\n  data: {f(D)}\n"
        f"rectification_matrix:\n  rows: 3\n  cols: 3\n  data: {f(R)}\n"
        f"projection_matrix:\n  rows: 3\n  cols: 4\n  data: {f(P)}\n")


w, h = 640, 480
stereo_R, _ = cv2.Rodrigues(np.array([0.01, -0.03, 0.005]))
stereo_T = np.array([[-0.12], [0.002], [0.001]])
pairs = {}
K1 = np.array([[520.0, 0, 318.5], [0, 521.0, 242.0], [0, 0, 1]])
D1 = np.array([-0.28, 0.09, 0.0008, -0.0004, -0.012])
K2 = np.array([[515.0, 0, 322.0], [0, 516.5, 238.5], [0, 0, 1]])
D2 = np.array([-0.27, 0.085, -0.0005, 0.0007, -0.01])
R1, R2, P1, P2 = cv2.stereoRectify(K1, D1, K2, D2, (w, h), stereo_R, stereo_T, alpha=0)[:4]
pairs["plumb_bob"] = [(K1, D1, R1, P1, cv2.initUndistortRectifyMap), (K2, D2, R2, P2, cv2.initUndistortRectifyMap)]
F1 = np.array([[300.0, 0, 321.0], [0, 300.5, 239.0], [0, 0, 1]])
G1 = np.array([0.03, -0.01, 0.002, -0.0004])
F2 = np.array([[298.0, 0, 318.0], [0, 299.0, 241.5], [0, 0, 1]])
G2 = np.array([0.028, -0.008, 0.0015, -0.0002])
R1, R2, P1, P2 = cv2.fisheye.stereoRectify(F1, G1, F2, G2, (w, h), stereo_R, stereo_T,
                                           flags=cv2.CALIB_ZERO_DISPARITY, balance=0.0)[:4]
fish_maps = lambda K, D, R, P, size, t: cv2.fisheye.initUndistortRectifyMap(K, D, R, P, size, t)
pairs["equidistant"] = [(F1, G1, R1, P1, fish_maps), (F2, G2, R2, P2, fish_maps)]
photo = smooth_image(w, h)
src = os.path.join(tmp, "stereo_photo.png")
cv2.imwrite(src, photo)
for model, sides in pairs.items():
    for side, (K, D, R, P, maps) in zip(["left", "right"], sides):
        info = os.path.join(tmp, f"{model}_{side}.yaml")
        camera_info(info, w, h, K, D, R, P, model)
        mx, my = maps(K, D, R, P, (w, h), cv2.CV_32FC1)
        theirs = cv2.remap(photo, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
        for backend in ["gpu", "cpu"]:
            out, mask = (os.path.join(tmp, f"{model}_{side}_{backend}_{s}.png") for s in ("vk", "mask"))
            said = subprocess.run([vklens, "undistort", "--camera", info, "--input", src, "--output", out,
                                   "--mask", mask, "--backend", backend],
                                  check=True, capture_output=True, text=True).stderr
            if "rectifying as image_proc does" not in said:
                failures.append(f"(d) {model} {side}: the CLI did not say it rectified: {said!r}")
            ours = cv2.imread(out)[..., :3]
            valid = cv2.imread(mask, cv2.IMREAD_GRAYSCALE) > 127
            inner = valid & (mx >= 0.5) & (my >= 0.5) & (mx <= w - 1.5) & (my <= h - 1.5)
            d = np.abs(ours.astype(int) - theirs.astype(int))[inner]
            print(f"  {model} {side} ({backend}): {inner.sum()} px compared, mean {d.mean():.5f}, max {d.max()} grey levels")
            if inner.sum() < 0.5 * w * h or d.mean() > 0.05 or d.max() > 1:
                failures.append(f"(d) {model} {side} {backend}: {inner.sum()} px, mean {d.mean():.5f} / max {d.max()}")
        # K alone differs: the rectification is not a no-op on this pair.
        out = os.path.join(tmp, f"{model}_{side}_k.png")
        run("undistort", "--no-rectification", "--camera", info, "--input", src, "--output", out)
        plain = np.abs(cv2.imread(out)[..., :3].astype(int) - theirs.astype(int)).mean()
        print(f"  {model} {side} with --no-rectification: mean {plain:.1f} grey levels from image_proc's")
        if plain < 5:
            failures.append(f"(d) {model} {side}: K alone is within {plain:.1f} levels of the rectified image")

if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("all OpenCV cross-checks passed")
