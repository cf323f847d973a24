"""Type stubs of the compiled module; the classes are re-exported by ``vklens``."""

import os
from typing import Any, List, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

PathLike = Union[str, "os.PathLike[str]"]
ArrayLike = npt.ArrayLike
Image = Union[npt.NDArray[np.uint8], npt.NDArray[np.uint16], npt.NDArray[np.float32]]

__version__: str

class Camera:
    """A calibrated camera: OpenCV's standard model (4, 5, 8, 12 or 14 coefficients, applied
    exactly as ``cv2.projectPoints``) or a Brown radial lens. Immutable; pickles as its JSON
    object."""

    def __init__(self, width: int, height: int, fx: float, fy: float, cx: float, cy: float,
                 dist_coeffs: Optional[ArrayLike] = None) -> None:
        """``dist_coeffs`` in OpenCV's order (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [τx τy]]]]),
        4, 5, 8, 12 or 14 of them; None is 5 zeros. Raises ``InputError`` naming the argument
        for a NaN, a non-positive focal length or another count."""
    @staticmethod
    def load(path: PathLike, camera_index: Optional[int] = None, camera_name: Optional[str] = None,
             size: Optional[Tuple[int, int]] = None) -> "Camera":
        """Any camera file the command line reads (docs/camera-files.md lists the formats:
        vklens JSON, OpenCV FileStorage, ROS ``camera_info``, Kalibr, Basalt, COLMAP, VINS,
        ORB-SLAM, OKVIS, EuRoC, SVO, DSO, stella_vslam, Kimera, Gyroflow, OCamCalib, NCore…).
        ``camera_index`` or ``camera_name`` (as the file writes it: ``cam1``, ``M2``, ``LEFT``,
        a COLMAP id) picks a camera of a file that holds several; ``size=(w, h)`` gives the
        image size to a file that has none. Raises ``InputError`` naming the file and key."""
    @staticmethod
    def list(path: PathLike, size: Optional[Tuple[int, int]] = None) -> List[dict]:
        """The cameras a file holds, one dict each: ``index``, ``name``, ``format`` and
        ``model``, ``width``, ``height``, or ``error`` (why it cannot load)."""
    def to_format(self, format: str) -> str:
        """The camera as another tool's file: ``"vklens"``, ``"opencv"``, ``"ros"``,
        ``"kalibr"``, ``"colmap"``, ``"basalt"``. Raises ``UnsupportedError`` where the format
        cannot hold the camera exactly."""
    @staticmethod
    def from_opencv(K: ArrayLike, D: ArrayLike, size: Tuple[int, int],
                    fisheye: bool = False) -> "Camera":
        """From OpenCV's ``K`` (3×3, row-major, no skew), ``D`` shaped ``(n,)``, ``(1, n)`` or
        ``(n, 1)``, and ``size = (width, height)``. With ``fisheye=True``: OpenCV's fisheye
        model (``cv2.fisheye``), ``D`` its four coefficients k1 k2 k3 k4 and ``K[0][1]`` its
        skew; without it, four coefficients are the standard model's k1 k2 p1 p2."""
    @overload
    def optimal_new_camera(self, alpha: float, new_size: Optional[Tuple[int, int]] = None,
                           center_principal_point: bool = False
                           ) -> Tuple["Camera", Tuple[int, int, int, int]]: ...
    @overload
    def optimal_new_camera(self, *, balance: float, fov_scale: float = 1.0,
                           new_size: Optional[Tuple[int, int]] = None
                           ) -> Tuple["Camera", Tuple[int, int, int, int]]: ...
    def optimal_new_camera(self, alpha: Optional[float] = None,
                           new_size: Optional[Tuple[int, int]] = None,
                           center_principal_point: bool = False, *,
                           balance: Optional[float] = None, fov_scale: Optional[float] = None
                           ) -> Tuple["Camera", Tuple[int, int, int, int]]:
        """The pinhole camera to undistort into, as OpenCV chooses it, and its valid ROI
        ``(x, y, w, h)``. ``alpha`` for OpenCV's standard model: the camera and ROI of
        ``cv2.getOptimalNewCameraMatrix(K, D, size, alpha, new_size, center_principal_point)``
        (0 keeps only pixels that have a source, 1 every source pixel). ``balance`` for its
        fisheye model: ``cv2.fisheye.estimateNewCameraMatrixForUndistortRectify(K, D, size,
        np.eye(3), balance=balance, new_size=new_size, fov_scale=fov_scale)``, with a valid
        ROI found as for ``alpha``. ``alpha`` and ``balance`` are exclusive; ``fov_scale`` goes
        with ``balance``, ``center_principal_point`` with ``alpha``.

        vklens undistorts with its converged inverse where ``cv2.undistortPoints`` stops after
        5 iterations: on a strong lens the cameras differ slightly (vklens's is the rule's
        exact answer). Raises ``InputError`` naming the keyword: ``alpha`` or ``balance``
        outside 0..1, ``fov_scale`` not positive, a zero ``new_size``, a camera of another
        model than the rule's, a lens that folds inside its image."""
    @staticmethod
    def from_dict(d: dict) -> "Camera":
        """From a vklens JSON camera object (what ``to_dict`` returns)."""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def size(self) -> Tuple[int, int]:
        """``(width, height)``."""
    @property
    def fx(self) -> float: ...
    @property
    def fy(self) -> float: ...
    @property
    def cx(self) -> float: ...
    @property
    def cy(self) -> float: ...
    @property
    def model(self) -> str:
        """``"opencv"``, ``"opencv_fisheye"``, ``"brown"`` or another model's name."""
    @property
    def K(self) -> npt.NDArray[np.float64]:
        """OpenCV's camera matrix, ``(3, 3)`` float64."""
    @property
    def dist_coeffs(self) -> npt.NDArray[np.float64]:
        """The coefficients as given, ``(n,)`` float64."""
    def to_dict(self) -> dict:
        """The vklens JSON camera object."""
    def save(self, path: PathLike) -> None:
        """Writes the camera as vklens JSON, atomically."""
    def distort_points(self, xy: ArrayLike) -> npt.NDArray[np.float64]:
        """Normalized undistorted ``(..., 2)`` (x = X/Z, y = Y/Z; any leading shape: ``(N, 2)``,
        OpenCV's ``(N, 1, 2)``, ``(H, W, 2)``) → distorted pixels in the same shape, float64,
        exact; NaN where the model is undefined."""
    def undistort_points(self, uv: ArrayLike, method: str = "newton", R: Optional[ArrayLike] = None,
                         P: Optional[ArrayLike] = None) -> npt.NDArray[np.float64]:
        """Distorted pixels ``(..., 2)`` → normalized undistorted, same shape; NaN outside the
        valid domain (the lens folds over there, or no preimage exists). ``method``:
        ``"newton"``, ``"heikkila"`` or ``"fixed-point:N"`` (OpenCV's own iteration). With
        ``R`` (3×3) and ``P`` (3×3 or 3×4) as ``cv2.undistortPoints(uv, K, D, R, P)``: the ray
        turned by ``R``, then pixels of ``P``; NaN where the turned ray points behind the image
        plane."""
    def unproject_points(self, uv: ArrayLike) -> NDArray[np.float64]:
        """Distorted pixels ``(..., 2)`` → unit camera-frame rays ``(..., 3)``; NaN outside the
        valid domain (a fisheye's rays reach past 90°: ``z < 0``)."""
    def project_points(self, points_3d: ArrayLike, rvec: Optional[ArrayLike] = None,
                       tvec: Optional[ArrayLike] = None, end_rvec: Optional[ArrayLike] = None,
                       end_tvec: Optional[ArrayLike] = None,
                       rolling_shutter: Optional[str] = None) -> npt.NDArray[np.float64]:
        """``(..., 3)`` world points → ``(..., 2)`` pixels, as ``cv2.projectPoints`` (``rvec`` a
        Rodrigues vector, ``rvec``/``tvec`` shaped ``(3,)``, ``(3, 1)`` or ``(1, 3)``); NaN rows
        for points the lens does not see (at or behind the camera; past a wide lens's field).

        Through a rolling shutter (``rolling_shutter``: ``"top_to_bottom"``, ``"bottom_to_top"``,
        ``"left_to_right"`` or ``"right_to_left"``; default: the camera file's own readout, an
        NCore ``shutter_type``, else a global shutter): ``rvec``/``tvec`` are the pose when the
        first line is read, ``end_rvec``/``end_tvec`` (together) when the last is, the rotation
        slerped and the centre moved linearly between; each point lands where its own line's
        readout time agrees with the pose it is seen from (solved to 1e-9 px; the first such
        time in readout order). ``end_rvec`` without a rolling shutter raises ``InputError``.
        See ``docs/rolling-shutter.md``."""

class Device:
    """A headless Vulkan device. ``VKLENS_DEVICE`` picks it as for the command line (``cpu``,
    ``gpu``, an index or part of the name; default: the fastest); ``VKLENS_VALIDATION=1`` turns
    the Khronos validation layer on."""

    def __init__(self) -> None: ...
    @staticmethod
    def default() -> "Device":
        """The one shared device used wherever ``device=None``."""
    @property
    def name(self) -> str: ...
    def check_validation(self) -> None:
        """Raises ``GpuError`` if the validation layer has reported anything so far."""

class Warper:
    """The post-processing warp, built once (pipelines, coordinate maps) and run on every
    frame. Thread-safe: calls on one Warper run one at a time, two Warpers run concurrently;
    the GIL is released while the device works."""

    def __init__(self, camera: Camera, direction: str = "distort", method: str = "lut",
                 chromatic: Optional[Sequence[float]] = None, source_camera: Optional[Camera] = None,
                 fill: Sequence[float] = (0, 0, 0, 0), device: Optional[Device] = None,
                 R: Optional[ArrayLike] = None, P: Optional[ArrayLike] = None,
                 interpolation: str = "bilinear", border: str = "constant") -> None:
        """Images: uint8, uint16, float32 or float64 (warped in float32, returned float64).
        ``direction``: ``"distort"`` (a pinhole image in, the lens image out),
        ``"undistort"`` (a lens image in, a pinhole image out) or ``"precorrect"`` (a headset
        pre-correction). ``method``: ``"lut"`` (a map built once), ``"newton"``, ``"heikkila"``
        or ``"fixed-point:N"`` (solved per pixel). ``chromatic``: R, G, B magnifications about
        the principal point (lateral chromatic aberration; channels are R, G, B in that
        order). ``source_camera``: the pinhole side's camera (for distort the input's, e.g.
        ``vklens.overscan(camera)``; otherwise the output's); None is the camera's own
        intrinsics. ``fill``: R, G, B, A in 0..1 for pixels without a source. ``R`` and
        ``P`` (undistort and precorrect): the rectification rotation (3×3) and the output
        camera (a 3×3 new camera matrix or a 3×4 projection matrix, at the camera's size), as
        ``cv2.initUndistortRectifyMap(K, D, R, P)`` and ROS ``image_proc`` rectify a stereo
        pair; ``P`` replaces ``source_camera``. ``interpolation``: ``"nearest"``,
        ``"bilinear"`` or ``"bicubic"`` (``cv2.INTER_NEAREST``, ``INTER_LINEAR``,
        ``INTER_CUBIC``; bicubic is OpenCV's kernel, overshoot included). ``border``: what a
        source position off the input reads, as ``cv2.remap``'s borders: ``"constant"`` (the
        pixel takes ``fill``, mask False), ``"replicate"`` (the edge repeats) or ``"reflect"``
        (the image mirrors, edge pixel included); pixels past the lens's valid domain take
        ``fill`` whatever the border."""
    @property
    def camera(self) -> Camera: ...
    @property
    def source_camera(self) -> Camera:
        """The pinhole side's camera actually used."""
    @property
    def input_size(self) -> Tuple[int, int]:
        """``(width, height)`` of the images it takes."""
    @property
    def output_size(self) -> Tuple[int, int]:
        """``(width, height)`` of the images it returns."""
    @property
    def direction(self) -> str: ...
    @property
    def method(self) -> str: ...
    @property
    def interpolation(self) -> str: ...
    @property
    def border(self) -> str: ...
    @property
    def device(self) -> Device: ...
    @overload
    def __call__(self, image: Image, out: Optional[Image] = None) -> Image: ...
    @overload
    def __call__(self, image: Image, out: Optional[Image] = None, *,
                 return_mask: bool) -> Any: ...
    def __call__(self, image: Image, out: Optional[Image] = None, return_mask: bool = False) -> Any:
        """Warps ``image`` (``(H, W)`` or ``(H, W, 1|3|4)``; uint8, uint16 or float32; any
        strides) and returns a new array of the same dtype and shape layout, or writes ``out``
        (C-contiguous, right shape and dtype) and returns it. With ``return_mask=True`` returns
        ``(out, mask)``, ``mask`` ``(H, W)`` bool, False where the pixel has no source in the
        valid domain."""
    def maps(self) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """``(map_x, map_y)``, each ``(H, W)`` float32, ready for ``cv2.remap``: per output
        pixel the source position its light comes from; NaN where it has none in the valid
        domain."""

def overscan(camera: Camera, density: float = 1.0) -> Camera:
    """The pinhole camera whose image covers every valid pixel of ``camera`` with ``density``
    source pixels per output pixel at the principal point (the distort warp's source)."""

class StereoRectification:
    """What ``stereo_rectify`` returns: ``cv2.stereoRectify``'s ``R1, R2, P1, P2, Q,
    validPixROI1, validPixROI2`` and the two rectified pinhole cameras. Read-only."""

    @property
    def R1(self) -> npt.NDArray[np.float64]:
        """The first camera's rectification rotation, ``(3, 3)`` float64."""
    @property
    def R2(self) -> npt.NDArray[np.float64]:
        """The second camera's rectification rotation, ``(3, 3)`` float64."""
    @property
    def P1(self) -> npt.NDArray[np.float64]:
        """The first rectified camera's projection, ``(3, 4)`` float64."""
    @property
    def P2(self) -> npt.NDArray[np.float64]:
        """The second's, its baseline times the focal length in the fourth column (row 1 for
        a vertical pair), ``(3, 4)`` float64."""
    @property
    def Q(self) -> npt.NDArray[np.float64]:
        """The disparity-to-depth matrix (``cv2.reprojectImageTo3D``'s), ``(4, 4)`` float64."""
    @property
    def roi1(self) -> Tuple[int, int, int, int]:
        """``(x, y, w, h)``: the first rectified image's valid pixels, as cv2's
        ``validPixROI1`` (the whole image for a fisheye pair)."""
    @property
    def roi2(self) -> Tuple[int, int, int, int]:
        """``(x, y, w, h)``: the second's."""
    @property
    def left(self) -> Camera:
        """The first rectified camera: pinhole, at the new size (``P1``'s 3×3 part)."""
    @property
    def right(self) -> Camera:
        """The second rectified camera (``P2``'s 3×3 part)."""
    @property
    def vertical(self) -> bool:
        """Whether the baseline runs along the image columns (OpenCV's vertical stereo,
        ``|T_y| > |T_x|``; never for a fisheye pair, which OpenCV always lays along the rows)."""
    @property
    def baseline(self) -> float:
        """The distance between the camera centres, in the units of ``T``."""

def stereo_rectify(left: Camera, right: Camera, R: ArrayLike, T: ArrayLike, *,
                   alpha: Optional[float] = None, new_size: Optional[Tuple[int, int]] = None,
                   zero_disparity: bool = True, balance: float = 0.0,
                   fov_scale: float = 1.0) -> StereoRectification:
    """The rectification of a calibrated pair, as OpenCV computes it: for two cameras of its
    standard model ``cv2.stereoRectify(K1, D1, K2, D2, size, R, T, flags=flags, alpha=alpha,
    newImageSize=new_size)``, for two of its fisheye model ``cv2.fisheye.stereoRectify(K1, D1,
    K2, D2, size, R, T, flags=flags, newImageSize=new_size, balance=balance,
    fov_scale=fov_scale)``, ``flags`` being ``cv2.CALIB_ZERO_DISPARITY`` when
    ``zero_disparity`` (OpenCV's default) and 0 otherwise. ``left`` is the first camera,
    ``right`` the second: X2 = R X1 + T, as ``cv2.stereoCalibrate`` reports them. ``R``: a 3×3
    rotation or a Rodrigues vector ``(3,)``, ``(3, 1)`` or ``(1, 3)``; ``T``: ``(3,)``,
    ``(3, 1)`` or ``(1, 3)``.

    ``alpha`` (standard model): None is OpenCV's -1 (no scaling), 0 keeps only pixels with a
    source in both images, 1 every source pixel of both. ``balance`` and ``fov_scale``
    (fisheye model) as ``cv2.fisheye.estimateNewCameraMatrixForUndistortRectify``'s.
    ``new_size``: the rectified images' ``(width, height)``; None is the cameras' own.

    vklens undistorts the image corners with its converged inverse where OpenCV's
    ``undistortPoints`` stops after 5 iterations: on a strong lens the rectified cameras differ
    slightly. Raises ``InputError`` naming the keyword: a camera of another model, two models
    or two image sizes (``left``, ``right``), an ``R`` that is not a rotation, a zero ``T``,
    ``alpha`` outside 0..1 or on a fisheye pair, ``balance`` or ``fov_scale`` on a standard
    pair, a lens or baseline OpenCV's rule has no camera for."""

def render_scene(scene: Union[PathLike, dict], device: Optional[Device] = None,
                 base: Optional[PathLike] = None) -> list:
    """Renders a scene file, or the same tables as a dict (relative paths resolved against
    ``base``, default the working folder): one dict per pose with ``"index"``, ``"ms"`` and the
    outputs the scene asks for: ``"color"`` (H, W, 4) uint8 or float32, ``"ids"`` (H, W)
    uint32, ``"flow"`` (H, W, 2) float32, ``"depth"`` (H, W) float32 (camera z),
    ``"range"`` (H, W) float32 (metres along each pixel's ray), ``"classes"`` (H, W) uint16,
    ``"boxes"`` (a list of dicts: ``id``, ``name``, ``class``, ``visible_px``,
    ``bbox_visible``, ``bbox_full``, ``corners_3d``, ``corners_visible``) and ``"keypoints"``
    (a list of dicts: ``name``, ``pixel`` or None, ``visible``); and ``"objects"``, every
    object's ``id``, ``name`` and ``class``. A dict's ``classes`` table keeps its order (the
    first matching pattern wins)."""
