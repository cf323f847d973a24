"""``cv2.fisheye``'s undistortion calls, computed by vklens for OpenCV's fisheye model
(Kannala–Brandt, ``D`` = k1 k2 k3 k4, ``K[0][1]`` its skew): ``vklens.compat.fisheye`` is to
``cv2.fisheye`` what ``vklens.compat`` is to ``cv2``. Rotations ``R`` are 3×3 or a rotation
vector, as cv2.fisheye takes them.

The skew ``K[0][1]`` is the lens's as ``cv2.fisheye.projectPoints`` applies it (and
``cv2.fisheye.calibrate`` estimates it); cv2's undistortion calls ignore it, so on a skewed
camera their maps and points are those of another lens."""

import numpy as np

from .._errors import Error
from . import _common as c
from ._common import CALIB_ZERO_DISPARITY

__all__ = [
    "initUndistortRectifyMap",
    "undistortImage",
    "undistortPoints",
    "estimateNewCameraMatrixForUndistortRectify",
    "stereoRectify",
    "CALIB_ZERO_DISPARITY",
]

_NAMES = {"K": "K", "D": "D", "size": "size"}


def initUndistortRectifyMap(K, D, R, P, size, m1type, map1=None, map2=None):
    """``(map1, map2)`` for ``cv2.remap``, as ``cv2.fisheye.initUndistortRectifyMap``: per pixel
    of the new ``size`` image, where its light comes from in the fisheye image.

    ``R``: rotation (None: the identity); ``P``: the new camera, 3×3 or 3×4 (None: the
    identity, as cv2, whose image then holds the view within a pixel of the axis). ``m1type``
    as in ``vklens.compat.initUndistortRectifyMap``; ``CV_32FC2``, which cv2.fisheye refuses,
    is given too. Pixels without a source (past where the lens's polynomial folds over, or
    whose ray points behind the camera) hold ``NO_SOURCE``, which ``cv2.remap`` fills with
    ``borderValue``; cv2.fisheye leaves maps it makes for ``m1type`` <= 0 unwritten (OpenCV
    5.1), compat writes them.
    The warper is cached as for ``vklens.compat.undistort``."""
    t = c.map_type(m1type)
    size = c.size_of(size, "size")
    lens = c.camera(K, D, size, True, _NAMES)
    R = c.rotation(R, "R", rodrigues=True)
    P = c.projection(P, "P")
    w = c.warper(lens, R, np.eye(3) if P is None else P, size, False, {"R": "R", "P": "P"})
    return c.maps(w, t, map1, map2)


def undistortImage(distorted, K, D, undistorted=None, Knew=None, new_size=None):
    """``distorted`` drawn through the pinhole ``Knew`` at ``new_size`` (default: its own size),
    bilinear with a black border, as ``cv2.fisheye.undistortImage``. ``Knew`` None is cv2's
    default, the identity matrix: pass a camera (``estimateNewCameraMatrixForUndistortRectify``
    or ``K``) for a useful image. Images, channels, ``undistorted`` and the cache as in
    ``vklens.compat.undistort``."""
    src = c.image(distorted, "distorted")
    h, w = src.shape[:2]
    lens = c.camera(K, D, (w, h), True, {**_NAMES, "size": "distorted"})
    P = c.projection(Knew, "Knew")
    size = c.size_of(new_size, "new_size", allow_zero=True) or (w, h)
    warper = c.warper(lens, None, np.eye(3) if P is None else P, size, True,
                      {"R": "R", "P": "Knew"})
    return c.warp_image(warper, src, undistorted)


def undistortPoints(distorted, K, D, undistorted=None, R=None, P=None, criteria=None):
    """The ideal points of fisheye pixels, as ``cv2.fisheye.undistortPoints``: normalized
    coordinates, turned by ``R``, in pixels of ``P`` where given. ``(N, 1, 2)`` and
    ``(1, N, 2)`` keep their shape, as in cv2; ``(N, 2)`` and ``(2,)``, which cv2.fisheye
    refuses, come back ``(N, 1, 2)``. float32 stays float32.

    The answer is the converged one whatever ``criteria`` says; inside the field of view cv2's
    default (Newton until a step moves θ less than 1e-8, at most 10 steps) has converged too,
    and the two agree to 1e-6 px. They differ where cv2's answer is not the lens's: NaN where
    no pinhole point exists, past where the lens folds over and for rays at or behind the
    (turned) image plane (a fisheye sees past 90°), where cv2 answers a number, having clipped
    the distorted angle at π/2; and cv2 ignores the skew ``K[0][1]``, which vklens applies."""
    uv, shape, dtype = c.points(distorted, "distorted", keep_row=True)
    lens = c.camera(K, D, (1, 1), True, _NAMES)
    R = c.rotation(R, "R", rodrigues=True)
    P = c.projection(P, "P")
    xy = lens.undistort_points(uv, R=R, P=P)
    return c.answer(xy, shape, dtype, undistorted)


def estimateNewCameraMatrixForUndistortRectify(K, D, image_size, R, P=None, balance=0.0,
                                               new_size=(0, 0), fov_scale=1.0):
    """The pinhole camera (3×3) to undistort into, as
    ``cv2.fisheye.estimateNewCameraMatrixForUndistortRectify``: ``balance`` 0 the largest focal
    length that fills the image from the edge midpoints, 1 the smallest, divided by
    ``fov_scale``; for ``new_size`` (``(0, 0)``: ``image_size``). ``P`` of shape (3, 3) float64
    is written in place.

    ``R`` must be the identity (None, ``np.eye(3)``, a zero rotation vector): vklens's rule is
    computed without a rotation, and a rectified pair's cameras come from ``stereoRectify``.
    ``balance`` outside 0..1 (which cv2 clamps) and a ``fov_scale`` that is not positive raise
    ``InputError``, as does a lens whose edge midpoints no pinhole image holds (cv2 answers a
    focal length near zero there)."""
    size = c.size_of(image_size, "image_size")
    lens = c.camera(K, D, size, True, {**_NAMES, "size": "image_size"})
    rot = c.rotation(R, "R", rodrigues=True)
    if rot is not None and not np.allclose(rot, np.eye(3), rtol=0, atol=1e-12):
        raise c.bad("R", "vklens estimates the new camera without a rotation: pass np.eye(3) or "
                         "None (a rectified pair's cameras: stereoRectify)")
    out_size = c.size_of(new_size, "new_size", allow_zero=True)
    try:
        new, _ = lens.optimal_new_camera(balance=c.real(balance, "balance"),
                                         fov_scale=c.real(fov_scale, "fov_scale"),
                                         new_size=out_size)
    except Error as e:
        raise c.renamed(e, {"camera": "D"}) from None
    return c._into(P, new.K)


def stereoRectify(K1, D1, K2, D2, imageSize, R, tvec, flags, R1=None, R2=None, P1=None, P2=None,
                  Q=None, newImageSize=(0, 0), balance=0.0, fov_scale=1.0):
    """``(R1, R2, P1, P2, Q)`` as ``cv2.fisheye.stereoRectify``: the rotations that make a
    fisheye pair's image planes one plane, the projections of the rectified views (their focal
    length chosen by ``balance`` and ``fov_scale`` as in
    ``estimateNewCameraMatrixForUndistortRectify``) and the disparity-to-depth matrix.
    ``flags``: 0 or ``CALIB_ZERO_DISPARITY``. ``R``: 3×3 or a rotation vector; ``tvec``:
    ``(3,)``, ``(3, 1)`` or ``(1, 3)``. Output arguments of the right shape and dtype are
    written in place."""
    rectify = c.stereo_rectify()
    size = c.size_of(imageSize, "imageSize")
    left = c.camera(K1, D1, size, True, {"K": "K1", "D": "D1", "size": "imageSize"})
    right = c.camera(K2, D2, size, True, {"K": "K2", "D": "D2", "size": "imageSize"})
    rot = c.rotation(R, "R", rodrigues=True)
    if rot is None:
        raise c.bad("R", "the rotation between the two cameras is required")
    t = c.translation(tvec, "tvec")
    zero_disparity = c.zero_disparity(flags)
    new_size = c.size_of(newImageSize, "newImageSize", allow_zero=True)
    try:
        r = rectify(left, right, rot, t, new_size=new_size, zero_disparity=zero_disparity,
                    balance=c.real(balance, "balance"), fov_scale=c.real(fov_scale, "fov_scale"))
    except Error as e:
        raise c.renamed(e, {"left": "K1", "right": "K2", "new_size": "newImageSize",
                            "zero_disparity": "flags", "T": "tvec"}) from None
    return c.rectification(r, (R1, R2, P1, P2, Q))
