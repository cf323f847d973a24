"""What ``vklens.compat`` and ``vklens.compat.fisheye`` share: reading OpenCV's argument forms,
the cache of built warpers, the remap maps in OpenCV's three layouts, and the image warp with
OpenCV's constant black border."""

import functools

import numpy as np

from .._errors import Error, InputError
from .._vklens import Camera, Warper

# OpenCV 4's type codes (CV_MAKETYPE(depth, channels) = depth + 8 (channels - 1)).
CV_16SC2 = 11
CV_32FC1 = 5
CV_32FC2 = 13
# OpenCV 5 widened the channel shift to 32: its cv2.CV_16SC2 is 35 and cv2.CV_32FC2 37. A
# script passes whichever its own cv2 defines, so both spellings are read (neither number means
# another map type in the other version).
_CV5_16SC2 = 35
_CV5_32FC2 = 37

CALIB_ZERO_DISPARITY = 1024

# What a map holds where vklens has no source for the pixel (NaN in Warper.maps()): the lowest
# int16, the same number in all three layouts, far outside any image, so that cv2.remap's
# default BORDER_CONSTANT gives those pixels borderValue under every interpolation.
NO_SOURCE = -32768.0

# Warpers built per distinct argument set; building one compiles pipelines and fills maps,
# which costs far more than a frame.
WARPER_CACHE_SIZE = 8


def bad(name, message):
    """An InputError led by, and carrying, the argument's name."""
    error = InputError(f"{name}: {message}")
    error.argument = name
    return error


def renamed(error, names):
    """A vklens error about one of its own arguments, under the name the cv2 call gives it."""
    old = getattr(error, "argument", None)
    new = names.get(old)
    if new is None:
        return error
    message = str(error)
    if message.startswith(old + ":"):
        message = new + message[len(old):]
    out = type(error)(message)
    out.argument = new
    return out


def _numbers(value, name):
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise bad(name, f"expected an array of numbers ({e})") from None
    return array


def is_empty(value):
    """OpenCV's "no matrix": None or an array with no elements."""
    return value is None or np.size(value) == 0


def matrix3(value, name):
    """A finite 3×3 matrix as float64."""
    m = _numbers(value, name)
    if m.shape != (3, 3):
        raise bad(name, f"shape {m.shape}; expected (3, 3)")
    if not np.isfinite(m).all():
        raise bad(name, "every entry must be a finite number")
    return m


def projection(value, name):
    """A new camera matrix (3×3) or projection matrix (3×4), as float64; None when empty."""
    if is_empty(value):
        return None
    m = _numbers(value, name)
    if m.shape not in ((3, 3), (3, 4)):
        raise bad(name, f"shape {m.shape}; expected (3, 3) or (3, 4)")
    if not np.isfinite(m).all():
        raise bad(name, "every entry must be a finite number")
    return m


def rotation(value, name, rodrigues):
    """A rectification rotation as a 3×3 float64, or None when empty (the identity). With
    ``rodrigues`` a rotation vector ``(3,)``, ``(1, 3)`` or ``(3, 1)`` is read as OpenCV's
    Rodrigues does, as the cv2 functions that take one do."""
    if is_empty(value):
        return None
    m = _numbers(value, name)
    if rodrigues and m.shape in ((3,), (1, 3), (3, 1)):
        if not np.isfinite(m).all():
            raise bad(name, "every entry must be a finite number")
        return rodrigues_matrix(m.ravel())
    if m.shape != (3, 3):
        want = ("(3, 3), or a rotation vector (3,), (1, 3) or (3, 1)" if rodrigues
                else "(3, 3) (this function takes no rotation vector)")
        raise bad(name, f"shape {m.shape}; expected {want}")
    if not np.isfinite(m).all():
        raise bad(name, "every entry must be a finite number")
    return m


def rodrigues_matrix(r):
    """The rotation by |r| radians about r / |r|."""
    theta = float(np.linalg.norm(r))
    if theta < np.finfo(np.float64).eps:
        return np.eye(3)
    k = r / theta
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    c, s = np.cos(theta), np.sin(theta)
    return c * np.eye(3) + (1.0 - c) * np.outer(k, k) + s * cross


def translation(value, name):
    t = _numbers(value, name)
    if t.shape not in ((3,), (1, 3), (3, 1)):
        raise bad(name, f"shape {t.shape}; expected (3,), (3, 1) or (1, 3)")
    if not np.isfinite(t).all():
        raise bad(name, "every entry must be a finite number")
    return t.ravel()


def coefficients(value, name, fisheye):
    """A distortion vector as a flat float64 array: ``(k,)``, ``(1, k)`` or ``(k, 1)``; None or
    empty is no distortion. Its count is checked by the camera model."""
    if is_empty(value):
        return np.zeros(4 if fisheye else 5)
    d = _numbers(value, name)
    if d.ndim > 2 or (d.ndim == 2 and 1 not in d.shape):
        raise bad(name, f"shape {d.shape}; expected (k,), (1, k) or (k, 1)")
    return d.ravel()


def size_of(value, name, allow_zero=False):
    """``(width, height)`` as two ints; ``(0, 0)`` (OpenCV's "not given") as None where allowed."""
    if value is None and allow_zero:
        return None
    try:
        w, h = (int(v) for v in value)
    except (TypeError, ValueError):
        raise bad(name, f"expected (width, height), got {value!r}") from None
    if allow_zero and (w, h) == (0, 0):
        return None
    if w <= 0 or h <= 0 or (w, h) != tuple(value):
        raise bad(name, f"expected two positive whole numbers (width, height), got {value!r}")
    return w, h


def camera(K, D, size, fisheye, names):
    """The vklens camera of OpenCV's K and D at ``size``; errors name the cv2 arguments
    (``names`` maps vklens's ``K``, ``D``, ``size`` to them)."""
    k = matrix3(K, names["K"])
    d = coefficients(D, names["D"], fisheye)
    try:
        return Camera.from_opencv(k, d, size, fisheye=fisheye)
    except Error as e:
        raise renamed(e, names) from None


def pinhole(P, size, name):
    """The pinhole camera of a new camera matrix (its 3×3 part) at ``size``."""
    k = P[:, :3]
    if k[0, 1] != 0.0 or k[1, 0] != 0.0 or tuple(k[2]) != (0.0, 0.0, 1.0):
        raise bad(name, f"{k.tolist()}: expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew)")
    try:
        return Camera(width=size[0], height=size[1], fx=k[0, 0], fy=k[1, 1], cx=k[0, 2], cy=k[1, 2])
    except Error as e:
        raise bad(name, str(e).split(": ", 1)[-1]) from None


def identity(R):
    return R is None or np.array_equal(R, np.eye(3))


# ---------------------------------------------------------------------------------------------
# Warpers


@functools.lru_cache(maxsize=WARPER_CACHE_SIZE)
def _cached(fisheye, k, d, r, p, source_size, output_size, border):
    """The undistort warper of one argument set, given as bytes (hashable, and equal exactly
    when the numbers are). ``border`` builds it for an image with a one-pixel black frame,
    which is how the image functions get OpenCV's constant border (see ``warp_image``)."""
    K = np.frombuffer(k, np.float64).reshape(3, 3).copy()
    D = np.frombuffer(d, np.float64)
    R = None if r is None else np.frombuffer(r, np.float64).reshape(3, 3)
    P = np.frombuffer(p, np.float64).reshape(3, 3)
    if border:
        # The same lens one pixel further in: its principal point moves with the frame.
        K[0, 2] += 1.0
        K[1, 2] += 1.0
        source_size = (source_size[0] + 2, source_size[1] + 2)
    lens = Camera.from_opencv(K, D, source_size, fisheye=fisheye)
    output = Camera(width=output_size[0], height=output_size[1], fx=P[0, 0], fy=P[1, 1],
                    cx=P[0, 2], cy=P[1, 2])
    return Warper(lens, direction="undistort", source_camera=output, R=R)


def warper(lens, R, P, output_size, border, names):
    """The cached undistort warper from ``lens`` (a vklens Camera) through the rotation ``R``
    (3×3 or None) into the pinhole ``P`` (3×3 or 3×4) at ``output_size``; errors name the
    cv2 arguments (``names`` maps ``"R"`` and ``"P"`` to them)."""
    pinhole(P, output_size, names["P"])
    k = np.ascontiguousarray(lens.K, np.float64)
    d = np.ascontiguousarray(lens.dist_coeffs, np.float64)
    fisheye = lens.model == "opencv_fisheye"
    r = None if identity(R) else np.ascontiguousarray(R, np.float64).tobytes()
    p = np.ascontiguousarray(P[:, :3], np.float64).tobytes()
    try:
        return _cached(fisheye, k.tobytes(), d.tobytes(), r, p, lens.size, tuple(output_size),
                       border)
    except Error as e:
        raise renamed(e, {"R": names["R"], "rectification": names["R"]}) from None


def cache_clear():
    """Drops every cached warper (their device memory goes with the last reference)."""
    _cached.cache_clear()


def cache_info():
    """``functools.lru_cache``'s hits, misses, maxsize and currsize of the warper cache."""
    return _cached.cache_info()


# ---------------------------------------------------------------------------------------------
# Maps


def map_type(m1type):
    """OpenCV's map type codes as one of CV_16SC2, CV_32FC1, CV_32FC2 (OpenCV 4's numbers)."""
    try:
        t = int(m1type)
    except (TypeError, ValueError):
        raise bad("m1type", f"expected an OpenCV type code, got {m1type!r}") from None
    if t != m1type:
        raise bad("m1type", f"expected an OpenCV type code, got {m1type!r}")
    if t <= 0 or t == _CV5_16SC2:
        return CV_16SC2
    if t == _CV5_32FC2:
        return CV_32FC2
    if t in (CV_16SC2, CV_32FC1, CV_32FC2):
        return t
    raise bad("m1type", f"{m1type} is not a map type; expected CV_32FC1 (5), CV_32FC2 (13), "
                        f"CV_16SC2 (11) or a value <= 0 (CV_16SC2, as OpenCV)")


def _into(out, value):
    """``out`` holding ``value`` where it has the right shape and dtype (OpenCV writes its
    output arguments in place then), else ``value`` itself."""
    if isinstance(out, np.ndarray) and out.shape == value.shape and out.dtype == value.dtype \
            and out.flags.writeable:
        out[...] = value
        return out
    return value


def fixed_point(map_x, map_y):
    """cv2.convertMaps's CV_16SC2 pair of float32 maps: the whole pixel as int16 (saturated)
    and the 1/32 px fraction of each axis packed into a uint16 index, y's 5 bits above x's."""
    def split(m):
        steps = np.rint(m.astype(np.float32) * np.float32(32)).astype(np.float64)
        steps = np.clip(steps, np.iinfo(np.int32).min, np.iinfo(np.int32).max).astype(np.int64)
        whole = np.clip(steps >> 5, -32768, 32767).astype(np.int16)
        return whole, (steps & 31).astype(np.uint16)

    x, fx = split(map_x)
    y, fy = split(map_y)
    return np.stack([x, y], axis=-1), fy * np.uint16(32) + fx


def maps(w, m1type, map1, map2):
    """The warper's maps in the layout ``m1type`` asks for, NO_SOURCE where it has none."""
    mx, my = w.maps()
    unmapped = np.isnan(mx) | np.isnan(my)
    mx[unmapped] = NO_SOURCE
    my[unmapped] = NO_SOURCE
    if m1type == CV_32FC1:
        return _into(map1, mx), _into(map2, my)
    if m1type == CV_32FC2:
        return _into(map1, np.stack([mx, my], axis=-1)), None
    xy, index = fixed_point(mx, my)
    return _into(map1, xy), _into(map2, index)


# ---------------------------------------------------------------------------------------------
# Images

_IMAGE_DTYPES = (np.uint8, np.uint16, np.int16, np.float32, np.float64)


def image(value, name):
    """An image as OpenCV's remap takes one: (H, W) or (H, W, C), of a dtype vklens warps."""
    if not isinstance(value, np.ndarray):
        raise bad(name, f"expected a numpy array, got {type(value).__name__}")
    if value.dtype not in _IMAGE_DTYPES:
        raise bad(name, f"dtype {value.dtype} is not supported; expected uint8, uint16, int16, "
                        f"float32 or float64")
    if value.ndim not in (2, 3) or value.shape[0] == 0 or value.shape[1] == 0 \
            or (value.ndim == 3 and value.shape[2] == 0):
        raise bad(name, f"shape {value.shape}; expected (H, W) or (H, W, channels)")
    return value


def warp_image(w, src, dst):
    """``src`` undistorted by ``w`` (built with ``border=True``) as cv2.remap with
    INTER_LINEAR and BORDER_CONSTANT 0 draws it, into ``dst`` where that has the output's shape
    and dtype.

    OpenCV blends a source position within one pixel outside the image with the black
    border; the warp samples the image's edge there instead. Framing the image in one black
    pixel, for a warper whose lens sits one pixel further in, gives OpenCV's blend exactly.
    Single-channel images come back (H, W), as cv2 returns them; channel counts the device has
    no format for (2, 5 and more) are warped in groups of up to four."""
    h, width = src.shape[:2]
    channels = 1 if src.ndim == 2 else src.shape[2]
    ow, oh = w.output_size
    shape = (oh, ow) if channels == 1 else (oh, ow, channels)
    framed = np.zeros((h + 2, width + 2, channels), src.dtype)
    framed[1:-1, 1:-1] = src.reshape(h, width, channels)
    if src.dtype == np.int16:
        # Exact in float32; OpenCV rounds its interpolated int16 samples to the nearest.
        framed = framed.astype(np.float32)
    groups = []
    for start in range(0, channels, 4):
        part = framed[:, :, start:start + 4]
        n = part.shape[2]
        if n == 2:
            part = np.concatenate([part, np.zeros_like(part[:, :, :1])], axis=2)
        if n == 1:
            part = part[:, :, 0]
        out = w(np.ascontiguousarray(part))
        groups.append(out.reshape(oh, ow, -1)[:, :, :n])
    result = groups[0] if len(groups) == 1 else np.concatenate(groups, axis=2)
    if src.dtype == np.int16:
        result = np.clip(np.rint(result), -32768, 32767).astype(np.int16)
    result = result.reshape(shape)
    if isinstance(dst, np.ndarray) and dst.dtype == src.dtype and dst.flags.writeable and (
            dst.shape == shape or (channels == 1 and dst.shape == (oh, ow, 1))):
        dst[...] = result.reshape(dst.shape)
        return dst
    return result


# ---------------------------------------------------------------------------------------------
# Points


def points(value, name, keep_row):
    """Pixels as cv2.undistortPoints reads them, ``(N, 1, 2)``, ``(1, N, 2)``, ``(N, 2)`` or one
    ``(2,)``: the ``(N, 2)`` float64 points, the shape and dtype the answer takes (float32 for
    float32 points, else float64; ``(N, 1, 2)``, or ``(1, N, 2)`` kept where ``keep_row``, as
    cv2.fisheye keeps it)."""
    a = np.asarray(value)
    if a.dtype.kind not in "fiu" or a.dtype == np.float16:
        raise bad(name, f"dtype {a.dtype}; expected float32 or float64 points")
    shape = a.shape
    if shape == (2,):
        a = a.reshape(1, 2)
    elif not (len(shape) == 2 and shape[1] == 2) and not (
            len(shape) == 3 and shape[2] == 2 and 1 in shape[:2]):
        raise bad(name, f"shape {shape}; expected (N, 1, 2), (1, N, 2), (N, 2) or (2,)")
    uv = a.reshape(-1, 2).astype(np.float64)
    out = (1, len(uv), 2) if keep_row and len(shape) == 3 and shape[0] == 1 and shape[1] != 1 \
        else (len(uv), 1, 2)
    dtype = np.float32 if a.dtype == np.float32 else np.float64
    return uv, out, dtype


def answer(xy, shape, dtype, dst):
    """Undistorted points in cv2's shape and dtype, into ``dst`` where that fits."""
    return _into(dst, xy.reshape(shape).astype(dtype))


def real(value, name):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise bad(name, f"expected a number, got {value!r}") from None
    if np.isnan(v):
        raise bad(name, "expected a number, got NaN")
    return v


def stereo_rectify():
    """The Rust-backed stereo rectification (imported late: vklens imports this package)."""
    from .._vklens import stereo_rectify as rectify

    return rectify


def zero_disparity(flags):
    """cv2.stereoRectify's flags: 0 or CALIB_ZERO_DISPARITY, the only flag it reads."""
    want = f"expected 0 or CALIB_ZERO_DISPARITY ({CALIB_ZERO_DISPARITY}), got {flags!r}"
    try:
        f = int(flags)
    except (TypeError, ValueError):
        raise bad("flags", want) from None
    if f != flags or f & ~CALIB_ZERO_DISPARITY:
        raise bad("flags", want)
    return bool(f & CALIB_ZERO_DISPARITY)


def rectification(r, outs):
    """A StereoRectification's R1, R2, P1, P2, Q as float64 arrays, into the output arguments
    ``outs`` where they fit."""
    values = (r.R1, r.R2, r.P1, r.P2, r.Q)
    return tuple(_into(o, np.asarray(v, np.float64)) for o, v in zip(outs, values))
