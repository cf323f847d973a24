"""OpenCV's undistortion calls, computed by vklens: a script that undistorts with cv2 changes
one import.

.. code-block:: python

    from vklens import compat as cv2          # was: import cv2

    K1, roi = cv2.getOptimalNewCameraMatrix(K, D, (w, h), 0.5)
    frame = cv2.undistort(frame, K, D, None, K1)
    map1, map2 = cv2.initUndistortRectifyMap(K, D, None, K1, (w, h), cv2.CV_16SC2)
    corners = cv2.undistortPoints(corners, K, D, P=K1)
    P = cv2.fisheye.estimateNewCameraMatrixForUndistortRectify(Kf, Df, (w, h), np.eye(3))

A script that also needs the rest of OpenCV keeps ``import cv2`` and imports this module as
``compat``: ``cv2.remap`` takes these maps as they are.

Every function takes cv2's arguments in cv2's order and under cv2's keywords, numpy arrays or
lists, and returns what cv2 returns: the same shapes, dtypes and tuples, output arguments
(``dst``, ``map1``, ``R1`` …) written in place where cv2 writes them (the right shape and
dtype) and a new array otherwise. Maps and images come from ``vklens.Warper`` on the device,
points from ``Camera.undistort_points``.

Where the answers differ from cv2's, cv2's is not the lens's: vklens iterates its inverse
until it has converged where cv2 stops after a fixed number of steps, and it answers NaN
(points), or leaves a pixel to the border (maps and images), where no source exists: the lens
folds over there, or the ray points behind the camera. cv2 answers a number there.
docs/compat.md lists the functions and each difference.

Bad input raises ``vklens.InputError`` (a ``ValueError``) naming cv2's argument.
"""

from .._errors import Error
from . import _common as c
from . import fisheye
from ._common import (CALIB_ZERO_DISPARITY, CV_16SC2, CV_32FC1, CV_32FC2, NO_SOURCE, cache_clear,
                      cache_info)

__all__ = [
    "initUndistortRectifyMap",
    "undistort",
    "undistortPoints",
    "getOptimalNewCameraMatrix",
    "stereoRectify",
    "fisheye",
    "CV_16SC2",
    "CV_32FC1",
    "CV_32FC2",
    "CALIB_ZERO_DISPARITY",
    "NO_SOURCE",
    "cache_clear",
    "cache_info",
]

_NAMES = {"K": "cameraMatrix", "D": "distCoeffs", "size": "size"}


def initUndistortRectifyMap(cameraMatrix, distCoeffs, R, newCameraMatrix, size, m1type,
                            map1=None, map2=None):
    """``(map1, map2)`` for ``cv2.remap``: per pixel of the new ``size`` image, where its light
    comes from in the lens image, as ``cv2.initUndistortRectifyMap``.

    ``m1type``: ``CV_32FC1`` (two ``(H, W)`` float32 maps), ``CV_32FC2`` (one ``(H, W, 2)``
    float32 map and ``None``) or ``CV_16SC2`` (OpenCV's fixed point: ``(H, W, 2)`` int16 whole
    pixels and an ``(H, W)`` uint16 table index of 1/32 px fractions, exactly what
    ``cv2.convertMaps`` makes of the float maps); a value <= 0 is ``CV_16SC2``, as in cv2.
    OpenCV 5's codes for the same types (``CV_16SC2`` 35, ``CV_32FC2`` 37) are read too.
    ``R``: a 3×3 rotation or None; ``newCameraMatrix``: 3×3, or a stereo pair's 3×4 ``P``;
    None is cv2's default, the camera's focal lengths with the principal point at the new
    image's centre.

    Where the pixel has no source (the lens folds over before it, or its ray turned by ``R``
    points behind the camera) both coordinates hold ``NO_SOURCE`` (-32768), far outside every
    image, so that ``cv2.remap`` with its default ``BORDER_CONSTANT`` gives it
    ``borderValue``; cv2's maps hold the folded lens's position there.

    The maps come from the device once per argument set: the warper is cached (the last 8,
    keyed on the values of K, D, R, the new camera and the size)."""
    t = c.map_type(m1type)
    size = c.size_of(size, "size")
    lens = c.camera(cameraMatrix, distCoeffs, size, False, _NAMES)
    R = c.rotation(R, "R", rodrigues=False)
    P = c.projection(newCameraMatrix, "newCameraMatrix")
    if P is None:
        P = lens.K.copy()
        P[0, 2], P[1, 2] = (size[0] - 1) * 0.5, (size[1] - 1) * 0.5
    w = c.warper(lens, R, P, size, False, {"R": "R", "P": "newCameraMatrix"})
    return c.maps(w, t, map1, map2)


def undistort(src, cameraMatrix, distCoeffs, dst=None, newCameraMatrix=None):
    """``src`` undistorted, as ``cv2.undistort``: drawn through ``newCameraMatrix`` (None: the
    camera's own), bilinear, black where the lens image has nothing (OpenCV's constant border,
    blended over the last pixel exactly as ``cv2.remap`` blends it).

    ``src``: ``(H, W)`` or ``(H, W, channels)``, uint8, uint16, int16, float32 or float64; a
    single channel comes back ``(H, W)`` as from cv2. ``dst`` of the output's shape and dtype
    is written in place and returned.

    Meant to be called once per frame: the warper (pipelines and maps, far slower to build
    than a frame is to warp) is cached per argument set, the last 8 kept, keyed on the values
    of K, D, the new camera and the image size. cv2 samples at positions rounded to 1/32 px;
    vklens at the exact ones, so a frame differs from cv2's by a fraction of a grey level."""
    src = c.image(src, "src")
    h, w = src.shape[:2]
    lens = c.camera(cameraMatrix, distCoeffs, (w, h), False, {**_NAMES, "size": "src"})
    P = c.projection(newCameraMatrix, "newCameraMatrix")
    if P is None:
        P = lens.K
    warper = c.warper(lens, None, P, (w, h), True, {"R": "R", "P": "newCameraMatrix"})
    return c.warp_image(warper, src, dst)


def undistortPoints(src, cameraMatrix, distCoeffs, dst=None, R=None, P=None, criteria=None):
    """The ideal points of distorted pixels, as ``cv2.undistortPoints``: normalized
    coordinates, turned by ``R`` (3×3) where given, in pixels of ``P`` (3×3 or 3×4) where
    given.

    ``src``: ``(N, 1, 2)``, ``(1, N, 2)``, ``(N, 2)`` or one ``(2,)`` point, float32 or float64
    (or integers and lists, as float64); the answer is ``(N, 1, 2)`` of the same float type, as
    cv2's. ``dst`` of that shape and dtype is written in place and returned.

    The answer is the converged one: cv2 runs 5 fixed-point iterations unless ``criteria``
    asks for more, which near the corners of a strong lens have not converged (on a 1280×720
    webcam with k1 = -0.31 the corner pixel's point is 1.6 px short, 1.7e-3 in normalized
    coordinates). vklens solves to the last bit whatever ``criteria`` says: it is taken for
    cv2's signature and not needed. NaN where the pixel has no undistorted point: past where
    the lens folds over, or where the ray turned by ``R`` points behind the camera (cv2 answers
    a number there)."""
    uv, shape, dtype = c.points(src, "src", keep_row=False)
    lens = c.camera(cameraMatrix, distCoeffs, (1, 1), False, _NAMES)
    R = c.rotation(R, "R", rodrigues=False)
    P = c.projection(P, "P")
    xy = lens.undistort_points(uv, R=R, P=P)
    return c.answer(xy, shape, dtype, dst)


def getOptimalNewCameraMatrix(cameraMatrix, distCoeffs, imageSize, alpha, newImgSize=None,
                              centerPrincipalPoint=False):
    """``(newCameraMatrix, validPixROI)`` as ``cv2.getOptimalNewCameraMatrix``: the pinhole
    camera that keeps only pixels with a source (``alpha`` 0), every source pixel (1), or a
    blend, and the ``(x, y, w, h)`` rectangle of valid pixels.

    OpenCV's rule bounds rectangles by a grid of undistorted edge pixels; vklens undistorts
    them with its converged inverse where cv2 stops after 5 iterations. On a mild lens the
    two agree to 1e-6; on a strong one cv2's corner points are not converged and the cameras
    differ (on a 1280×720 webcam with k1 = -0.31 by 0.05 % of the focal length at alpha 0,
    0.2 % at alpha 1, the rectangle's sides a third of a pixel off the image's edges), vklens's
    being the rule's exact answer. ``alpha`` outside 0..1, which cv2 extrapolates to, raises
    ``InputError``; so does a lens that folds inside its image (cv2's rectangles mean nothing
    there)."""
    size = c.size_of(imageSize, "imageSize")
    lens = c.camera(cameraMatrix, distCoeffs, size, False, {**_NAMES, "size": "imageSize"})
    new_size = c.size_of(newImgSize, "newImgSize", allow_zero=True)
    try:
        new, roi = lens.optimal_new_camera(c.real(alpha, "alpha"), new_size,
                                           bool(centerPrincipalPoint))
    except Error as e:
        raise c.renamed(e, {"new_size": "newImgSize", "camera": "distCoeffs",
                            "center_principal_point": "centerPrincipalPoint"}) from None
    return new.K, tuple(int(v) for v in roi)


def stereoRectify(cameraMatrix1, distCoeffs1, cameraMatrix2, distCoeffs2, imageSize, R, T,
                  R1=None, R2=None, P1=None, P2=None, Q=None, flags=CALIB_ZERO_DISPARITY,
                  alpha=-1, newImageSize=(0, 0)):
    """``(R1, R2, P1, P2, Q, validPixROI1, validPixROI2)`` as ``cv2.stereoRectify``: the
    rotations that make a calibrated pair's image planes one plane, the projections of the
    rectified views, the disparity-to-depth matrix and each view's rectangle of valid pixels.

    ``R``: 3×3 or a rotation vector; ``T``: ``(3,)``, ``(3, 1)`` or ``(1, 3)``; ``flags``: 0 or
    ``CALIB_ZERO_DISPARITY`` (the principal points made equal); ``alpha`` -1 (any negative)
    is cv2's default scaling, else 0..1 as in ``getOptimalNewCameraMatrix``;
    ``newImageSize`` (0, 0) is ``imageSize``. The output arguments of the right shape and dtype
    are written in place. The valid rectangles come from the converged inverse, as in
    ``getOptimalNewCameraMatrix``."""
    rectify = c.stereo_rectify()
    size = c.size_of(imageSize, "imageSize")
    left = c.camera(cameraMatrix1, distCoeffs1, size, False,
                    {"K": "cameraMatrix1", "D": "distCoeffs1", "size": "imageSize"})
    right = c.camera(cameraMatrix2, distCoeffs2, size, False,
                     {"K": "cameraMatrix2", "D": "distCoeffs2", "size": "imageSize"})
    rot = c.rotation(R, "R", rodrigues=True)
    if rot is None:
        raise c.bad("R", "the rotation between the two cameras is required")
    t = c.translation(T, "T")
    zero_disparity = c.zero_disparity(flags)
    alpha = c.real(alpha, "alpha")
    new_size = c.size_of(newImageSize, "newImageSize", allow_zero=True)
    try:
        r = rectify(left, right, rot, t, alpha=None if alpha < 0 else alpha, new_size=new_size,
                    zero_disparity=zero_disparity)
    except Error as e:
        raise c.renamed(e, {"left": "cameraMatrix1", "right": "cameraMatrix2",
                            "new_size": "newImageSize", "zero_disparity": "flags"}) from None
    return c.rectification(r, (R1, R2, P1, P2, Q)) + (tuple(r.roi1), tuple(r.roi2))
