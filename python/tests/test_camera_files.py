"""Calibration files in Python: picking a camera by name, index and size, listing what a file
holds, and writing a camera in another tool's format, checked against the real readers and
writers where a package ships them (OpenCV's FileStorage, pycolmap's text reconstruction)."""

import numpy as np
import pytest

import vklens

cv2 = pytest.importorskip("cv2")
pycolmap = pytest.importorskip("pycolmap")

KALIBR = """cam0:
  camera_model: pinhole
  intrinsics: [461.6, 460.3, 366.3, 249.3]
  distortion_model: radtan
  distortion_coeffs: [-0.27, 0.06, 1.2e-4, 2.2e-5]
  resolution: [752, 480]
cam1:
  camera_model: ds
  intrinsics: [-0.2, 0.57, 349.7, 348.9, 365.8, 249.9]
  distortion_model: none
  resolution: [752, 480]
"""


def directions(n=400):
    rng = np.random.default_rng(5)
    t = rng.uniform(0, np.radians(75), n)
    phi = rng.uniform(0, 2 * np.pi, n)
    return np.column_stack([np.sin(t) * np.cos(phi), np.sin(t) * np.sin(phi), np.cos(t)])


def test_cameras_by_name_index_and_listing(tmp_path):
    path = tmp_path / "camchain.yaml"
    path.write_text(KALIBR)
    listing = vklens.Camera.list(str(path))
    assert [(c["index"], c["name"], c["model"]) for c in listing] == [(0, "cam0", "opencv"), (1, "cam1", "double_sphere")]
    assert {c["format"] for c in listing} == {"Kalibr camchain"}
    by_name = vklens.Camera.load(str(path), camera_name="cam1")
    by_index = vklens.Camera.load(str(path), camera_index=1)
    assert by_name.model == "double_sphere"
    P = directions()
    assert np.array_equal(by_name.project_points(P), by_index.project_points(P))
    assert vklens.Camera.load(str(path)).model == "opencv"
    with pytest.raises(vklens.InputError, match="cam7") as e:
        vklens.Camera.load(str(path), camera_name="cam7")
    assert e.value.argument == "camera_name" and str(e.value).startswith("camera_name: ")
    with pytest.raises(vklens.InputError, match="752") as e:
        vklens.Camera.load(str(path), size=(640, 480))
    assert e.value.argument == "size"
    with pytest.raises(vklens.InputError) as e:
        vklens.Camera.load(str(path), camera_index=0, camera_name="cam1")
    assert e.value.argument is None


def test_opencv_stereo_file_written_by_cv2(tmp_path):
    """A stereo calibration as cv2.FileStorage writes it (stereo_calib's M1 D1 M2 D2): each
    camera by its key projects as cv2.projectPoints does."""
    M1 = np.array([[700.1, 0, 319.4], [0, 699.7, 241.2], [0, 0, 1]])
    D1 = np.array([[-0.29, 0.11, 4e-4, -2e-4, -0.02]])
    M2 = np.array([[702.3, 0, 322.8], [0, 701.9, 238.6], [0, 0, 1]])
    D2 = np.array([[-0.28, 0.1, -3e-4, 1e-4, -0.018]])
    for ext in ("yml", "xml"):
        path = str(tmp_path / f"intrinsics.{ext}")
        fs = cv2.FileStorage(path, cv2.FILE_STORAGE_WRITE)
        for key, value in (("M1", M1), ("D1", D1), ("M2", M2), ("D2", D2)):
            fs.write(key, value)
        fs.release()
        # The file has no image size: it loads only with one.
        with pytest.raises(vklens.InputError, match="size"):
            vklens.Camera.load(path, camera_name="M2")
        names = [c.get("name") for c in vklens.Camera.list(path, size=(640, 480))]
        assert names == ["M1", "M2"]
        P = directions()
        for key, K, D in (("M1", M1, D1), ("M2", M2, D2)):
            cam = vklens.Camera.load(path, camera_name=key, size=(640, 480))
            want, _ = cv2.projectPoints(P.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, D)
            err = np.abs(cam.project_points(P) - want.reshape(-1, 2)).max()
            assert err < 1e-9, f"{ext} {key}: {err} px"


def test_to_format_is_read_back_by_opencv_and_pycolmap(tmp_path):
    cam = vklens.Camera(752, 480, 458.654, 457.296, 367.215, 248.375,
                        dist_coeffs=[-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05])
    # OpenCV's own FileStorage reads the opencv file vklens writes.
    path = str(tmp_path / "cam.yml")
    with open(path, "w") as f:
        f.write(cam.to_format("opencv"))
    fs = cv2.FileStorage(path, cv2.FILE_STORAGE_READ)
    K = fs.getNode("camera_matrix").mat()
    D = fs.getNode("distortion_coefficients").mat()
    assert int(fs.getNode("image_width").real()) == 752
    fs.release()
    assert np.array_equal(K, [[458.654, 0, 367.215], [0, 457.296, 248.375], [0, 0, 1]])
    assert np.array_equal(D.ravel()[:4], [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05])

    # pycolmap reads the cameras.txt vklens writes, and projects the same pixels (its centres
    # at +0.5).
    fisheye = vklens.Camera(width=752, height=480, fx=190.9, fy=190.8, cx=254.9, cy=256.9,
                            model="opencv_fisheye", dist_coeffs=[-0.013, 0.017, -0.012, 0.003])
    for c in (cam, fisheye):
        d = tmp_path / f"sparse_{c.model}"
        d.mkdir()
        (d / "cameras.txt").write_text(c.to_format("colmap"))
        (d / "images.txt").write_text("")
        (d / "points3D.txt").write_text("")
        rec = pycolmap.Reconstruction()
        rec.read_text(str(d))
        ref = rec.cameras[1]
        P = directions()
        want = np.asarray(ref.img_from_cam(P), dtype=np.float64) - 0.5
        err = np.abs(c.project_points(P) - want).max()
        assert err < 1e-9, f"{c.model}: {err} px from pycolmap"

    # Every format round-trips through vklens itself; the ones that cannot hold a double
    # sphere say so.
    ds = vklens.Camera(width=752, height=480, fx=349.7, fy=348.9, cx=365.8, cy=249.9,
                       model="double_sphere", xi=-0.2, alpha=0.57)
    for fmt, ext in (("vklens", "json"), ("kalibr", "yaml"), ("basalt", "json")):
        p = tmp_path / f"ds_{fmt}.{ext}"
        p.write_text(ds.to_format(fmt))
        back = vklens.Camera.load(str(p))
        P = directions()
        assert np.allclose(back.project_points(P), ds.project_points(P), rtol=0, atol=1e-9)
    for fmt in ("opencv", "ros", "colmap"):
        with pytest.raises(vklens.UnsupportedError, match="cannot hold"):
            ds.to_format(fmt)
    with pytest.raises(vklens.InputError, match="basalt"):
        ds.to_format("matlab")
