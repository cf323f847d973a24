"""Shared fixtures: the reference data in ../shared (VKLENS_SHARED overrides), the release
binary (the Rust library's own answers, for the checks that compare with it), one device."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import vklens

REPO = pathlib.Path(__file__).resolve().parents[2]
SHARED = pathlib.Path(os.environ.get("VKLENS_SHARED", REPO.parent / "shared"))


def pytest_configure(config):
    # Every GPU test runs under the Khronos validation layer; `device` fails on any message.
    os.environ.setdefault("VKLENS_VALIDATION", "1")


@pytest.fixture(scope="session")
def reference():
    path = SHARED / "reference" / "opencv_standard_model.json"
    assert path.exists(), f"reference data missing: {path} (set VKLENS_SHARED)"
    return {c["name"]: c for c in json.loads(path.read_text())["cases"]}


def camera_of(case):
    return vklens.Camera(
        width=case["width"], height=case["height"], fx=case["fx"], fy=case["fy"],
        cx=case["cx"], cy=case["cy"], dist_coeffs=case["dist_coeffs"],
    )


def k_d(case):
    K = np.array([[case["fx"], 0, case["cx"]], [0, case["fy"], case["cy"]], [0, 0, 1]], float)
    return K, np.array(case["dist_coeffs"], float)


@pytest.fixture(scope="session")
def calibration_files():
    return SHARED / "reference" / "calibration-files"


@pytest.fixture(scope="session")
def cli():
    """The release binary: the Rust library's answers, through its command line."""
    exe = REPO / "target" / "release" / "vklens"
    if not exe.exists():
        subprocess.run(["cargo", "build", "--release", "--bin", "vklens"], cwd=REPO, check=True)
    return exe


@pytest.fixture(scope="session")
def device():
    d = vklens.Device.default()
    yield d
    d.check_validation()


def smooth_image(w, h, channels=3, dtype=np.uint8):
    """Sinusoids with periods of 30-60 px: smooth enough that OpenCV's 1/32 px map quantization
    moves values by well under a grey level."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    planes = [
        128 + 100 * np.sin(x / 9.0) * np.cos(y / 11.0),
        128 + 100 * np.sin((x + y) / 13.0),
        128 + 100 * np.cos(x / 7.0 - y / 17.0),
        200 + 40 * np.sin(y / 15.0),
    ]
    img = np.clip(np.dstack(planes[:channels]), 0, 255) / 255.0
    if dtype == np.uint8:
        img = (img * 255).round().astype(np.uint8)
    elif dtype == np.uint16:
        img = (img * 65535).round().astype(np.uint16)
    else:
        img = img.astype(dtype)
    return img[:, :, 0] if channels == 1 else img
