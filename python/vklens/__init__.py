"""vklens: calibrated camera-lens distortion on Vulkan, with numpy arrays in and out.

OpenCV's standard model (all 14 coefficients, exactly as ``cv2.projectPoints``) with a safe
inverse that answers NaN where no inverse can be right, a GPU warp that distorts, undistorts
or pre-corrects images in-process, and scene rendering through the lens.

>>> import vklens, numpy as np
>>> cam = vklens.Camera(width=800, height=600, fx=400, fy=400, cx=399.5, cy=299.5,
...                     dist_coeffs=[-0.05, 0.01, 0.0, 0.0])
>>> cam.distort_points(np.array([[0.0, 0.0]]))
array([[399.5, 299.5]])
"""

from ._errors import Error, GpuError, InputError, InternalError, IoError, UnsupportedError
from ._vklens import (Camera, Device, StereoRectification, Warper, __version__, overscan,
                      render_scene, stereo_rectify)

__all__ = [
    "Camera",
    "Device",
    "Warper",
    "StereoRectification",
    "stereo_rectify",
    "overscan",
    "render_scene",
    "Error",
    "InputError",
    "GpuError",
    "UnsupportedError",
    "IoError",
    "InternalError",
    "__version__",
]
