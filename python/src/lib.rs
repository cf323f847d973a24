//! The compiled half of the `vklens` Python package: a thin layer over the crate's public
//! surface (`vklens::Camera`, `Device`, `Warper`, `overscan`, `SceneRenderer`) that turns
//! numpy arrays into borrowed host images and back, releases the GIL while the device works,
//! and maps every `vklens::Error` onto the Python exception of its kind (`vklens/_errors.py`).

use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use numpy::ndarray::IxDyn;
use numpy::{
    Element, PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple, PyType};

use vklens::rolling_shutter::{Readout, WorldToCamera};
use vklens::{
    Border, Camera, Device, ErrorKind, HostImage, HostImageMut, HostPixels, HostPixelsMut,
    InverseMethod, PixelFormat, Pixels, Sampling, SceneRenderer, WarpDirection, WarpMethod,
    WarpOptions, Warper,
};

// ---------------------------------------------------------------------------------------------
// Errors

/// The Python exception class for `kind`, from the pure-Python `vklens._errors`.
fn raise(py: Python<'_>, kind: ErrorKind, message: String) -> PyErr {
    let name = match kind {
        ErrorKind::Input => "InputError",
        ErrorKind::Unsupported => "UnsupportedError",
        ErrorKind::Vulkan => "GpuError",
        ErrorKind::Io => "IoError",
        _ => "InternalError",
    };
    let class = py
        .import("vklens._errors")
        .and_then(|m| m.getattr(name))
        .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
    match class {
        Ok(class) => PyErr::from_type(class, message),
        Err(e) => e,
    }
}

/// A `vklens::Error` as the Python exception of its kind. An error about one argument leads
/// with its keyword (the library's argument names are the Python keywords) and carries it as
/// the exception's `argument` attribute.
fn to_py(py: Python<'_>, e: vklens::Error) -> PyErr {
    match e.argument_name() {
        Some(argument) => {
            let err = raise(py, e.kind(), format!("{argument}: {}", e.message_only()));
            let _ = err.value(py).setattr("argument", argument);
            err
        }
        None => raise(py, e.kind(), e.to_string()),
    }
}

/// `InputError(message)`.
fn input(py: Python<'_>, message: impl Into<String>) -> PyErr {
    raise(py, ErrorKind::Input, message.into())
}

/// `InputError("argument: message")` with the exception's `argument` set, as for the
/// library's own argument errors.
fn input_arg(py: Python<'_>, argument: &str, message: impl std::fmt::Display) -> PyErr {
    let err = raise(py, ErrorKind::Input, format!("{argument}: {message}"));
    let _ = err.value(py).setattr("argument", argument);
    err
}

trait OrPy<T> {
    /// The error as its Python exception.
    fn py(self, py: Python<'_>) -> PyResult<T>;
    /// The error as its Python exception, its message led by the argument it is about.
    fn arg(self, py: Python<'_>, name: &str) -> PyResult<T>;
}

impl<T> OrPy<T> for vklens::Result<T> {
    fn py(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| to_py(py, e))
    }
    fn arg(self, py: Python<'_>, name: &str) -> PyResult<T> {
        self.map_err(|e| {
            let text = e.message_only();
            let text = if text.starts_with(name) {
                text
            } else {
                format!("{name}: {text}")
            };
            let err = raise(py, e.kind(), text);
            let _ = err.value(py).setattr("argument", name);
            err
        })
    }
}

/// A lock whose poisoning (a panic on another thread, already reported there) is ignored: the
/// warper behind it stays consistent, every run stages all it reads.
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

// ---------------------------------------------------------------------------------------------
// Arrays of numbers (points, K, D, rvec, tvec)

/// `value` as float64 numbers with their shape. Ints and lists convert (they are exact);
/// anything that is not numbers raises `InputError` naming `name`.
fn numbers(
    py: Python<'_>,
    value: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let np = py.import("numpy")?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", "float64")?;
    let array = np
        .call_method("asarray", (value,), Some(&kwargs))
        .map_err(|e| input_arg(py, name, format!("expected an array of numbers ({e})")))?;
    let array = array
        .cast_into::<PyArrayDyn<f64>>()
        .map_err(|_| input_arg(py, name, "expected an array of numbers"))?;
    let shape = array.shape().to_vec();
    let data = array.readonly().as_array().iter().copied().collect();
    Ok((data, shape))
}

/// A shape as Python writes it: `(3,)`, `(480, 640, 3)`.
fn tuple(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Points of `D` numbers along the last axis, in any leading shape (`(D,)`, `(N, D)`, OpenCV's
/// `(N, 1, D)`, an image's `(H, W, D)`): the points and that leading shape, which the answer
/// keeps.
fn rows<const D: usize>(
    py: Python<'_>,
    value: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<(Vec<[f64; D]>, Vec<usize>)> {
    let (data, shape) = numbers(py, value, name)?;
    let Some((_, leading)) = shape.split_last().filter(|(&d, _)| d == D) else {
        return Err(input_arg(
            py,
            name,
            format!(
                "shape {}; expected (..., {D}): {D} numbers per point, in any leading shape ((N, {D}), OpenCV's (N, 1, {D}), …)",
                tuple(&shape)
            ),
        ));
    };
    let points = data
        .chunks_exact(D)
        .map(|c| std::array::from_fn(|i| c[i]))
        .collect();
    Ok((points, leading.to_vec()))
}

/// A vector of `n` numbers given as `(n,)`, `(1, n)` or `(n, 1)` (any `n` when `n` is None).
fn vector(
    py: Python<'_>,
    value: &Bound<'_, PyAny>,
    name: &str,
    n: Option<usize>,
) -> PyResult<Vec<f64>> {
    let (data, shape) = numbers(py, value, name)?;
    let flat = matches!(shape.as_slice(), [_] | [1, _] | [_, 1]);
    if !flat || n.is_some_and(|n| data.len() != n) {
        let want = n.map_or("n".to_string(), |n| n.to_string());
        return Err(input_arg(
            py,
            name,
            format!(
                "shape {}; expected ({want},), (1, {want}) or ({want}, 1)",
                tuple(&shape)
            ),
        ));
    }
    Ok(data)
}

/// A finite 3×3 matrix (row-major), or the left 3×3 of a 3×4 one where `allow_3x4` (a
/// projection matrix P, whose fourth column is a stereo baseline the warp does not use).
fn matrix3(
    py: Python<'_>,
    value: &Bound<'_, PyAny>,
    name: &str,
    allow_3x4: bool,
) -> PyResult<[[f64; 3]; 3]> {
    let (data, shape) = numbers(py, value, name)?;
    let cols = match shape.as_slice() {
        [3, 3] => 3,
        [3, 4] if allow_3x4 => 4,
        _ => {
            return Err(input_arg(
                py,
                name,
                format!(
                    "shape {}; expected (3, 3){}",
                    tuple(&shape),
                    if allow_3x4 { " or (3, 4)" } else { "" }
                ),
            ))
        }
    };
    if data.iter().any(|v| !v.is_finite()) {
        return Err(input_arg(py, name, "every entry must be a finite number"));
    }
    Ok(std::array::from_fn(|i| {
        std::array::from_fn(|j| data[i * cols + j])
    }))
}

/// The pinhole camera of a projection matrix P (its 3×3 part: `[[fx, 0, cx], [0, fy, cy],
/// [0, 0, 1]]`) at `size`.
fn camera_of_p(py: Python<'_>, p: [[f64; 3]; 3], size: (u32, u32)) -> PyResult<Camera> {
    if p[0][1] != 0.0 || p[1][0] != 0.0 || p[2] != [0.0, 0.0, 1.0] {
        return Err(input_arg(
            py,
            "P",
            format!("{p:?}: expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew)"),
        ));
    }
    Camera::from_opencv(p, &[0.0; 4], size).arg(py, "P")
}

/// Answers of `N` numbers per point, float64, in the points' leading shape; NaN where the
/// model gave no answer.
fn nan_rows<'py, const N: usize>(
    py: Python<'py>,
    v: Vec<Option<[f64; N]>>,
    leading: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let flat: Vec<f64> = v
        .into_iter()
        .flat_map(|p| p.unwrap_or([f64::NAN; N]))
        .collect();
    let shape: Vec<usize> = leading.iter().copied().chain([N]).collect();
    PyArray1::from_vec(py, flat).reshape(shape)
}

fn method(py: Python<'_>, name: &str) -> PyResult<InverseMethod> {
    name.parse::<InverseMethod>()
        .map_err(|e| input_arg(py, "method", e))
}

/// A whole, non-negative pixel count.
fn side(py: Python<'_>, v: i64, name: &str) -> PyResult<u32> {
    u32::try_from(v).map_err(|_| {
        input_arg(
            py,
            name,
            format!("{v} is not a pixel count (1..=4294967295)"),
        )
    })
}

// ---------------------------------------------------------------------------------------------
// Camera

/// A calibrated camera: OpenCV's standard model (4, 5, 8, 12 or 14 coefficients, exactly as
/// ``cv2.projectPoints``), its fisheye model, a Brown radial lens or another model of the table.
#[pyclass(name = "Camera", module = "vklens", frozen)]
#[derive(Clone)]
struct PyCamera {
    inner: Camera,
}

#[pymethods]
impl PyCamera {
    #[new]
    #[pyo3(signature = (width, height, fx = None, fy = None, cx = None, cy = None, dist_coeffs = None, model = None, **params))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        width: i64,
        height: i64,
        fx: Option<f64>,
        fy: Option<f64>,
        cx: Option<f64>,
        cy: Option<f64>,
        dist_coeffs: Option<&Bound<'_, PyAny>>,
        model: Option<String>,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        if model.as_deref().is_some_and(|m| m != "opencv") || params.is_some_and(|p| !p.is_empty())
        {
            // Every other model: the keywords are its vklens JSON keys, read by the one reader
            // camera files go through.
            let mut obj = serde_json::Map::new();
            obj.insert(
                "model".into(),
                model.unwrap_or_else(|| "opencv".into()).into(),
            );
            obj.insert("width".into(), width.into());
            obj.insert("height".into(), height.into());
            for (key, v) in [("fx", fx), ("fy", fy), ("cx", cx), ("cy", cy)] {
                if let Some(v) = v {
                    obj.insert(key.into(), v.into());
                }
            }
            if let Some(d) = dist_coeffs {
                obj.insert(
                    "dist_coeffs".into(),
                    vector(py, d, "dist_coeffs", None)?.into(),
                );
            }
            for (key, value) in params.into_iter().flat_map(|p| p.iter()) {
                let key: String = key.extract()?;
                // A bool first: Python's True is also an int, which would read as 1.0.
                let v = if value.is_instance_of::<pyo3::types::PyBool>() {
                    serde_json::Value::from(value.extract::<bool>()?)
                } else if let Ok(s) = value.extract::<String>() {
                    serde_json::Value::from(s)
                } else if let Ok(x) = value.extract::<f64>() {
                    serde_json::Value::from(x)
                } else {
                    serde_json::Value::from(vector(py, &value, &key, None)?)
                };
                obj.insert(key, v);
            }
            let text = serde_json::Value::Object(obj).to_string();
            return Ok(PyCamera {
                inner: Camera::parse(&text, "Camera(...)").py(py)?,
            });
        }
        let (Some(fx), Some(fy), Some(cx), Some(cy)) = (fx, fy, cx, cy) else {
            return Err(input(
                py,
                "Camera(width, height, fx, fy, cx, cy, dist_coeffs): fx, fy, cx and cy are required for OpenCV's standard model",
            ));
        };
        let d = match dist_coeffs {
            Some(d) => vector(py, d, "dist_coeffs", None)?,
            None => vec![0.0; 5],
        };
        let k = [[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]];
        let size = (side(py, width, "width")?, side(py, height, "height")?);
        let inner = Camera::from_opencv(k, &d, size)
            .map_err(|e| named(py, e, "fx, fy, cx, cy", "dist_coeffs", "width, height"))?;
        Ok(PyCamera { inner })
    }

    /// Reads any camera file the command line reads (``vklens cameras FILE`` says what a file
    /// holds). ``camera_index`` or ``camera_name`` (as the file writes it: ``cam1``, ``M2``,
    /// ``LEFT``, a COLMAP id) picks a camera of a file that holds several; ``size=(w, h)``
    /// gives the image size to a file that has none.
    #[staticmethod]
    #[pyo3(signature = (path, camera_index = None, camera_name = None, size = None))]
    fn load(
        py: Python<'_>,
        path: PathBuf,
        camera_index: Option<usize>,
        camera_name: Option<String>,
        size: Option<(i64, i64)>,
    ) -> PyResult<Self> {
        let options = vklens::LoadOptions {
            index: camera_index,
            name: camera_name,
            size: size
                .map(|s| Ok::<_, PyErr>((side(py, s.0, "size")?, side(py, s.1, "size")?)))
                .transpose()?,
        };
        Ok(PyCamera {
            inner: Camera::load_with(&path, &options).py(py)?,
        })
    }

    /// The cameras a calibration file holds, as ``vklens cameras --json`` lists them: one
    /// dict per camera with ``index``, ``name``, ``format`` and ``model``, ``width``,
    /// ``height`` (or ``error``, why it cannot load). ``size=(w, h)`` for a file without one.
    #[staticmethod]
    #[pyo3(signature = (path, size = None))]
    fn list(py: Python<'_>, path: PathBuf, size: Option<(i64, i64)>) -> PyResult<Vec<Py<PyAny>>> {
        let size = size
            .map(|s| Ok::<_, PyErr>((side(py, s.0, "size")?, side(py, s.1, "size")?)))
            .transpose()?;
        let listing = Camera::list(&path, size).py(py)?;
        let mut out = Vec::new();
        for (index, found) in listing.cameras.iter().enumerate() {
            let d = PyDict::new(py);
            d.set_item("index", index)?;
            d.set_item("name", &found.name)?;
            d.set_item("format", listing.format)?;
            match &found.camera {
                Ok(c) => {
                    d.set_item("model", c.model_name())?;
                    d.set_item("width", c.width)?;
                    d.set_item("height", c.height)?;
                }
                Err(e) => d.set_item("error", e.to_string())?,
            }
            out.push(d.into_any().unbind());
        }
        Ok(out)
    }

    /// The camera in another tool's format, as text: ``"vklens"``, ``"opencv"``, ``"ros"``,
    /// ``"kalibr"``, ``"colmap"``, ``"basalt"`` (``vklens convert``). Raises
    /// ``UnsupportedError`` where the format cannot hold the camera exactly.
    fn to_format(&self, py: Python<'_>, format: &str) -> PyResult<String> {
        let format: vklens::CameraFormat = format.parse().py(py)?;
        self.inner.to_format(format).py(py)
    }

    /// From OpenCV's ``K`` (3×3, row-major) and ``D`` (any OpenCV length, shaped ``(n,)``,
    /// ``(1, n)`` or ``(n, 1)``) and the image size ``(width, height)``. With ``fisheye=True``
    /// the camera is OpenCV's fisheye model (``cv2.fisheye``): ``D`` is its k1 k2 k3 k4 and
    /// ``K[0][1]`` its skew; otherwise four coefficients are the standard model's k1 k2 p1 p2.
    #[staticmethod]
    #[pyo3(name = "from_opencv", signature = (k, d, size, fisheye = false))]
    fn from_opencv_(
        py: Python<'_>,
        k: &Bound<'_, PyAny>,
        d: &Bound<'_, PyAny>,
        size: (i64, i64),
        fisheye: bool,
    ) -> PyResult<Self> {
        let (kv, shape) = numbers(py, k, "K")?;
        if shape != [3, 3] {
            return Err(input(
                py,
                format!("K: shape {}; expected (3, 3)", tuple(&shape)),
            ));
        }
        let km = [
            [kv[0], kv[1], kv[2]],
            [kv[3], kv[4], kv[5]],
            [kv[6], kv[7], kv[8]],
        ];
        let dv = vector(py, d, "D", None)?;
        let size = (side(py, size.0, "size")?, side(py, size.1, "size")?);
        let inner = if fisheye {
            Camera::from_opencv_fisheye(km, &dv, size)
        } else {
            Camera::from_opencv(km, &dv, size)
        }
        .map_err(|e| named(py, e, "K", "D", "size"))?;
        Ok(PyCamera { inner })
    }

    /// The pinhole camera to undistort into, as OpenCV chooses it, and its valid ROI
    /// ``(x, y, w, h)``: ``(Camera, roi)``.
    ///
    /// ``alpha`` (OpenCV's standard model): ``cv2.getOptimalNewCameraMatrix(K, D, size, alpha,
    /// new_size, center_principal_point)``; 0 keeps only pixels that have a source, 1 every
    /// source pixel. ``balance`` (its fisheye model):
    /// ``cv2.fisheye.estimateNewCameraMatrixForUndistortRectify(K, D, size, I, balance=...,
    /// new_size=..., fov_scale=...)``. Give one of the two.
    #[pyo3(signature = (alpha = None, new_size = None, center_principal_point = false, *, balance = None, fov_scale = None))]
    fn optimal_new_camera(
        &self,
        py: Python<'_>,
        alpha: Option<f64>,
        new_size: Option<(i64, i64)>,
        center_principal_point: bool,
        balance: Option<f64>,
        fov_scale: Option<f64>,
    ) -> PyResult<(PyCamera, (u32, u32, u32, u32))> {
        let new_size = new_size
            .map(|s| Ok::<_, PyErr>((side(py, s.0, "new_size")?, side(py, s.1, "new_size")?)))
            .transpose()?;
        let (camera, roi) = match (alpha, balance) {
            (Some(_), Some(_)) => {
                return Err(input_arg(
                    py,
                    "balance",
                    "alpha and balance are exclusive: alpha chooses by cv2.getOptimalNewCameraMatrix's rule (OpenCV's standard model), balance by cv2.fisheye.estimateNewCameraMatrixForUndistortRectify's (its fisheye model); give one",
                ))
            }
            (None, None) => {
                return Err(input_arg(
                    py,
                    "alpha",
                    format!(
                        "give alpha= (OpenCV's standard model: cv2.getOptimalNewCameraMatrix) or balance= (its fisheye model: cv2.fisheye.estimateNewCameraMatrixForUndistortRectify); this camera is `{}`",
                        self.inner.model_name()
                    ),
                ))
            }
            (Some(alpha), None) => {
                if fov_scale.is_some() {
                    return Err(input_arg(
                        py,
                        "fov_scale",
                        "fov_scale goes with balance= (the fisheye rule); alpha's rule has none",
                    ));
                }
                py.detach(|| {
                    vklens::optimal_new_camera(
                        &self.inner,
                        alpha,
                        new_size,
                        center_principal_point,
                    )
                })
                .py(py)?
            }
            (None, Some(balance)) => {
                if center_principal_point {
                    return Err(input_arg(
                        py,
                        "center_principal_point",
                        "center_principal_point goes with alpha= (cv2.getOptimalNewCameraMatrix); the fisheye rule centres the edge midpoints itself",
                    ));
                }
                let fov_scale = fov_scale.unwrap_or(1.0);
                py.detach(|| {
                    vklens::fisheye_new_camera(&self.inner, balance, fov_scale, new_size)
                })
                .py(py)?
            }
        };
        Ok((PyCamera { inner: camera }, roi))
    }

    /// From a vklens JSON camera object (what ``to_dict`` returns).
    #[staticmethod]
    fn from_dict(py: Python<'_>, d: &Bound<'_, PyAny>) -> PyResult<Self> {
        let text: String = py
            .import("json")?
            .call_method1("dumps", (d,))
            .map_err(|e| input(py, format!("camera dict: {e}")))?
            .extract()?;
        Ok(PyCamera {
            inner: Camera::parse(&text, "camera dict").py(py)?,
        })
    }

    #[getter]
    fn width(&self) -> u32 {
        self.inner.width
    }
    #[getter]
    fn height(&self) -> u32 {
        self.inner.height
    }
    #[getter]
    fn fx(&self) -> f64 {
        self.inner.intrinsics.fx
    }
    #[getter]
    fn fy(&self) -> f64 {
        self.inner.intrinsics.fy
    }
    #[getter]
    fn cx(&self) -> f64 {
        self.inner.intrinsics.cx
    }
    #[getter]
    fn cy(&self) -> f64 {
        self.inner.intrinsics.cy
    }
    /// ``(width, height)``.
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.inner.width, self.inner.height)
    }
    /// ``"opencv"``, ``"opencv_fisheye"`` or ``"brown"``.
    #[getter]
    fn model(&self) -> &'static str {
        self.inner.model_name()
    }
    /// OpenCV's camera matrix, ``(3, 3)`` float64.
    #[getter(K)]
    fn k<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let k = self.inner.k_matrix();
        PyArray1::from_vec(py, k.iter().flatten().copied().collect()).reshape([3, 3])
    }
    /// The distortion coefficients, as many as given, ``(n,)`` float64.
    #[getter]
    fn dist_coeffs<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.dist_coeffs())
    }

    /// The vklens JSON camera object, as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?
            .call_method1("loads", (self.inner.to_json().to_string(),))
    }

    /// Writes the camera as vklens JSON (atomically).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        self.inner.save(&path).py(py)
    }

    /// Normalized undistorted ``(x, y)`` → distorted pixels, ``(..., 2)`` float64 in the
    /// points' own leading shape, exact (f64 on
    /// the CPU); NaN rows where the model is undefined.
    fn distort_points<'py>(
        &self,
        py: Python<'py>,
        xy: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (xy, leading) = rows::<2>(py, xy, "xy")?;
        let uv = py.detach(|| self.inner.distort_points(&xy));
        nan_rows(py, uv, &leading)
    }

    /// Distorted pixels → normalized undistorted ``(x, y)``; NaN rows outside the valid domain
    /// (where the lens folds over, or no preimage exists). ``method``: ``"newton"``,
    /// ``"heikkila"`` or ``"fixed-point:N"``. With ``R`` (3×3 rectification rotation) and ``P``
    /// (3×3 new camera matrix, or a 3×4 projection matrix) as ``cv2.undistortPoints(uv, K, D,
    /// R, P)``: the ray turned by ``R``, then pixels of ``P`` (normalized coordinates without
    /// it); NaN where the turned ray points behind the image plane.
    #[pyo3(signature = (uv, method = "newton", R = None, P = None))]
    #[allow(non_snake_case)]
    fn undistort_points<'py>(
        &self,
        py: Python<'py>,
        uv: &Bound<'py, PyAny>,
        method: &str,
        R: Option<&Bound<'py, PyAny>>,
        P: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let m = self::method(py, method)?;
        self.inner
            .check_method(m)
            .map_err(|e| input_arg(py, "method", e))?;
        let r = R.map(|r| matrix3(py, r, "R", false)).transpose()?;
        let p = P.map(|p| matrix3(py, p, "P", true)).transpose()?;
        let (uv, leading) = rows::<2>(py, uv, "uv")?;
        let xy = py.detach(|| match (r, p) {
            (None, None) => self.inner.undistort_points(&uv, m),
            (r, p) => self.inner.undistort_points_rectified(&uv, m, r, p),
        });
        nan_rows(py, xy, &leading)
    }

    /// Distorted pixels ``(..., 2)`` → unit camera-frame rays ``(..., 3)``; NaN rows outside the
    /// valid domain. A fisheye's rays reach past 90° off the axis (``z < 0``).
    fn unproject_points<'py>(
        &self,
        py: Python<'py>,
        uv: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (uv, leading) = rows::<2>(py, uv, "uv")?;
        let rays = py.detach(|| self.inner.unproject_points(&uv));
        nan_rows(py, rays, &leading)
    }

    /// World points ``(..., 3)`` → distorted pixels ``(..., 2)``, as ``cv2.projectPoints`` with
    /// ``rvec`` (Rodrigues) and ``tvec``; NaN rows for points the lens does not see (at or
    /// behind the camera for the standard model; past its field of view for a fisheye).
    ///
    /// Through a rolling shutter (``rolling_shutter``: ``"top_to_bottom"``,
    /// ``"bottom_to_top"``, ``"left_to_right"``, ``"right_to_left"``; default: the camera
    /// file's own readout, else a global shutter), ``rvec``/``tvec`` are the pose when the first
    /// line is read and ``end_rvec``/``end_tvec`` when the last is (default: the same pose);
    /// each point lands where its own line's readout time agrees with the pose it is seen from.
    #[pyo3(signature = (points_3d, rvec = None, tvec = None, end_rvec = None, end_tvec = None, rolling_shutter = None))]
    #[allow(clippy::too_many_arguments)]
    fn project_points<'py>(
        &self,
        py: Python<'py>,
        points_3d: &Bound<'py, PyAny>,
        rvec: Option<&Bound<'py, PyAny>>,
        tvec: Option<&Bound<'py, PyAny>>,
        end_rvec: Option<&Bound<'py, PyAny>>,
        end_tvec: Option<&Bound<'py, PyAny>>,
        rolling_shutter: Option<&str>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (points, leading) = rows::<3>(py, points_3d, "points_3d")?;
        let pose =
            |r: Option<&Bound<'py, PyAny>>, t: Option<&Bound<'py, PyAny>>, names: [&str; 2]| {
                let r = match r {
                    Some(r) => vector(py, r, names[0], Some(3))?,
                    None => vec![0.0; 3],
                };
                let t = match t {
                    Some(t) => vector(py, t, names[1], Some(3))?,
                    None => vec![0.0; 3],
                };
                if r.iter().chain(&t).any(|v| !v.is_finite()) {
                    return Err(input(
                        py,
                        format!(
                            "{}, {}: every entry must be a finite number",
                            names[0], names[1]
                        ),
                    ));
                }
                Ok((rodrigues([r[0], r[1], r[2]]), [t[0], t[1], t[2]]))
            };
        let (rot, t) = pose(rvec, tvec, ["rvec", "tvec"])?;
        let end = match (end_rvec, end_tvec) {
            (None, None) => None,
            (Some(_), Some(_)) => Some(pose(end_rvec, end_tvec, ["end_rvec", "end_tvec"])?),
            (given, _) => {
                let (has, missing) = if given.is_some() {
                    ("end_rvec", "end_tvec")
                } else {
                    ("end_tvec", "end_rvec")
                };
                return Err(input_arg(
                    py,
                    missing,
                    format!("missing beside {has}: end_rvec and end_tvec come together (the pose when the last line is read)"),
                ));
            }
        };
        let readout = match rolling_shutter {
            Some(name) => Some(
                name.parse::<Readout>()
                    .map_err(|e| input_arg(py, "rolling_shutter", e))?,
            ),
            None => self.inner.readout(),
        };
        let Some(readout) = readout else {
            if end.is_some() {
                return Err(input_arg(
                    py,
                    "end_rvec",
                    "a pose when the last line is read needs a rolling shutter, and the shutter is global (every line read at once, from rvec, tvec): give rolling_shutter=\"top_to_bottom\" (or bottom_to_top, left_to_right, right_to_left)",
                ));
            }
            let cam: Vec<[f64; 3]> = points
                .iter()
                .map(|p| {
                    std::array::from_fn(|i| {
                        rot[i][0] * p[0] + rot[i][1] * p[1] + rot[i][2] * p[2] + t[i]
                    })
                })
                .collect();
            let uv = py.detach(|| self.inner.project_points(&cam));
            return nan_rows(py, uv, &leading);
        };
        let start = WorldToCamera::from_rows(rot, t);
        let end = end.map_or(start, |(r, t)| WorldToCamera::from_rows(r, t));
        let uv: Vec<Option<[f64; 2]>> = py.detach(|| {
            self.inner
                .project_points_rolling(&points, &start, &end, readout)
                .into_iter()
                .map(|p| p.map(|p| p.pixel.to_array()))
                .collect()
        });
        nan_rows(py, uv, &leading)
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        let k = c.intrinsics;
        if c.model().is_ray_model() && c.fisheye_lens().is_none() {
            let params: Vec<String> = c
                .lens()
                .params()
                .iter()
                .map(|(n, v)| format!("{n}={v}"))
                .collect();
            return format!(
                "Camera(model='{}', {}×{}, fx={}, fy={}, cx={}, cy={}, {})",
                c.model_name(),
                c.width,
                c.height,
                k.fx,
                k.fy,
                k.cx,
                k.cy,
                params.join(", ")
            );
        }
        if c.fisheye_lens().is_some() {
            return format!(
                "Camera(model='opencv_fisheye', {}×{}, fx={}, fy={}, cx={}, cy={}, k={:?})",
                c.width,
                c.height,
                k.fx,
                k.fy,
                k.cx,
                k.cy,
                c.dist_coeffs()
            );
        }
        match c.brown() {
            Some(b) => format!(
                "Camera(model='brown', {}×{}, c1={}, c2={})",
                c.width, c.height, b.c1, b.c2
            ),
            None => format!(
                "Camera({}×{}, fx={}, fy={}, cx={}, cy={}, dist_coeffs={:?})",
                c.width,
                c.height,
                k.fx,
                k.fy,
                k.cx,
                k.cy,
                c.dist_coeffs()
            ),
        }
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyCamera>()
            .is_ok_and(|o| o.get().inner.to_json() == self.inner.to_json())
    }

    /// Pickles as its JSON object (Ray, multiprocessing).
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let from_dict = py.get_type::<PyCamera>().getattr("from_dict")?;
        let dict = slf.get().to_dict(py)?;
        Ok((from_dict, PyTuple::new(py, [dict])?))
    }
}

/// A model error from `Camera::from_opencv`, led by the argument it is about: `coeffs` (the
/// distortion vector's name) for a coefficient or their count, `size` for the image size.
/// An error of `Camera::from_opencv` in the words of the Python call that made it: the
/// library's `K`, `dist_coeffs` and `size` arguments under the names this call gives them.
fn named(py: Python<'_>, e: vklens::Error, k: &str, coeffs: &str, size: &str) -> PyErr {
    let Some(argument) = e.argument_name() else {
        return to_py(py, e);
    };
    let name = match argument {
        "K" => k,
        "dist_coeffs" => coeffs,
        "size" => size,
        other => other,
    };
    let err = raise(py, e.kind(), format!("{name}: {}", e.message_only()));
    let _ = err.value(py).setattr("argument", name);
    err
}

/// OpenCV's Rodrigues rotation: the axis `r / |r|` turned by `|r|` radians.
fn rodrigues(r: [f64; 3]) -> [[f64; 3]; 3] {
    let theta = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
    if theta < f64::EPSILON {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let k = r.map(|v| v / theta);
    let (s, c) = theta.sin_cos();
    let cross = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let id = if i == j { 1.0 } else { 0.0 };
            c * id + (1.0 - c) * k[i] * k[j] + s * cross[i][j]
        })
    })
}

// ---------------------------------------------------------------------------------------------
// Device

/// One shared default device, opened on first use (device start-up is the slow part).
static DEFAULT_DEVICE: Mutex<Option<Arc<Device>>> = Mutex::new(None);

fn default_device(py: Python<'_>) -> PyResult<Arc<Device>> {
    py.detach(|| {
        let mut d = lock(&DEFAULT_DEVICE);
        if let Some(d) = d.as_ref() {
            return Ok(d.clone());
        }
        let device = Arc::new(Device::new()?);
        *d = Some(device.clone());
        Ok(device)
    })
    .py(py)
}

/// A headless Vulkan device. ``VKLENS_DEVICE`` picks it as for the command line (``cpu``,
/// ``gpu``, an index or part of the name); ``VKLENS_VALIDATION=1`` turns the Khronos
/// validation layer on.
#[pyclass(name = "Device", module = "vklens", frozen)]
struct PyDevice {
    inner: Arc<Device>,
}

#[pymethods]
impl PyDevice {
    #[new]
    fn new(py: Python<'_>) -> PyResult<Self> {
        let inner = py.detach(Device::new).py(py)?;
        Ok(PyDevice {
            inner: Arc::new(inner),
        })
    }

    /// The default device every ``Warper`` and ``render_scene`` use when given none.
    #[staticmethod]
    fn default(py: Python<'_>) -> PyResult<Self> {
        Ok(PyDevice {
            inner: default_device(py)?,
        })
    }

    /// The device's name, as the driver reports it.
    #[getter]
    fn name(&self) -> String {
        self.inner.name().to_string()
    }

    /// Raises ``GpuError`` if the validation layer (when on) has reported anything.
    fn check_validation(&self, py: Python<'_>) -> PyResult<()> {
        self.inner.check_validation().py(py)
    }

    fn __repr__(&self) -> String {
        format!("Device({:?})", self.inner.name())
    }
}

fn device_or_default(py: Python<'_>, device: Option<PyRef<'_, PyDevice>>) -> PyResult<Arc<Device>> {
    match device {
        Some(d) => Ok(d.inner.clone()),
        None => default_device(py),
    }
}

// ---------------------------------------------------------------------------------------------
// Warper

/// The sample types a Warper takes, each with the host view of its slices.
trait Sample: Element + Copy + Send + Sync {
    /// Warped on the float pipeline (16-bit and float images) rather than the 8-bit one.
    const FLOAT: bool;
    fn host(s: &[Self]) -> HostPixels<'_>;
    fn host_mut(s: &mut [Self]) -> HostPixelsMut<'_>;
}

impl Sample for u8 {
    const FLOAT: bool = false;
    fn host(s: &[u8]) -> HostPixels<'_> {
        HostPixels::U8(s)
    }
    fn host_mut(s: &mut [u8]) -> HostPixelsMut<'_> {
        HostPixelsMut::U8(s)
    }
}

impl Sample for u16 {
    const FLOAT: bool = true;
    fn host(s: &[u16]) -> HostPixels<'_> {
        HostPixels::U16(s)
    }
    fn host_mut(s: &mut [u16]) -> HostPixelsMut<'_> {
        HostPixelsMut::U16(s)
    }
}

impl Sample for f32 {
    const FLOAT: bool = true;
    fn host(s: &[f32]) -> HostPixels<'_> {
        HostPixels::F32(s)
    }
    fn host_mut(s: &mut [f32]) -> HostPixelsMut<'_> {
        HostPixelsMut::F32(s)
    }
}

/// One coordinate map, `(H, W)` float32.
type Map<'py> = Bound<'py, PyArray2<f32>>;

/// The post-processing warp, built once (device, pipelines, maps) and run on every frame.
#[pyclass(name = "Warper", module = "vklens", frozen)]
struct PyWarper {
    device: Arc<Device>,
    camera: Camera,
    options: WarpOptions,
    direction: &'static str,
    method: String,
    /// The 8-bit pipeline, built with the warper.
    rgba8: Mutex<Warper>,
    /// The float pipeline (16-bit and float32 images), built on the first such frame.
    rgba32f: Mutex<Option<Warper>>,
    source_camera: Camera,
    input_size: (u32, u32),
    output_size: (u32, u32),
}

#[pymethods]
impl PyWarper {
    #[new]
    #[pyo3(signature = (camera, direction = "distort", method = "lut", chromatic = None,
                        source_camera = None, fill = None, device = None, R = None, P = None,
                        interpolation = "bilinear", border = "constant"),
           text_signature = "(camera, direction='distort', method='lut', chromatic=None, source_camera=None, fill=(0, 0, 0, 0), device=None, R=None, P=None, interpolation='bilinear', border='constant')")]
    #[allow(clippy::too_many_arguments, non_snake_case)]
    fn new(
        py: Python<'_>,
        camera: PyRef<'_, PyCamera>,
        direction: &str,
        method: &str,
        chromatic: Option<&Bound<'_, PyAny>>,
        source_camera: Option<PyRef<'_, PyCamera>>,
        fill: Option<&Bound<'_, PyAny>>,
        device: Option<PyRef<'_, PyDevice>>,
        R: Option<&Bound<'_, PyAny>>,
        P: Option<&Bound<'_, PyAny>>,
        interpolation: &str,
        border: &str,
    ) -> PyResult<Self> {
        let dir: WarpDirection = direction.parse().arg(py, "direction")?;
        let m: WarpMethod = method.parse().arg(py, "method")?;
        let sampling: Sampling = interpolation.parse().arg(py, "interpolation")?;
        let border: Border = border.parse().arg(py, "border")?;
        let mut options = match dir {
            WarpDirection::Distort => WarpOptions::distort(),
            WarpDirection::Undistort => WarpOptions::undistort(),
            WarpDirection::Precorrect => WarpOptions::precorrect(),
        };
        options.method = m;
        options.sampling = sampling;
        options.border = border;
        if let Some(c) = chromatic {
            let c = vector(py, c, "chromatic", Some(3))?;
            options.chromatic = Some([c[0], c[1], c[2]]);
        }
        options.source_camera = source_camera.map(|c| c.inner.clone());
        if let Some(r) = R {
            if dir == WarpDirection::Distort {
                return Err(input_arg(
                    py,
                    "R",
                    "a rectification rotation applies to a pinhole output: direction='undistort'",
                ));
            }
            options.rectification = Some(matrix3(py, r, "R", false)?);
        }
        if let Some(p) = P {
            if dir == WarpDirection::Distort {
                return Err(input_arg(
                    py,
                    "P",
                    "the output camera P applies to a pinhole output: direction='undistort' (distort takes source_camera)",
                ));
            }
            if options.source_camera.is_some() {
                return Err(input_arg(
                    py,
                    "P",
                    "give the output camera once: P or source_camera",
                ));
            }
            let size = (camera.inner.width, camera.inner.height);
            options.source_camera = Some(camera_of_p(py, matrix3(py, p, "P", true)?, size)?);
        }
        let f = match fill {
            Some(f) => vector(py, f, "fill", Some(4))?,
            None => vec![0.0; 4],
        };
        if f.iter().any(|v| !v.is_finite()) {
            return Err(input(py, "fill: every value must be a finite number"));
        }
        options.fill = [f[0] as f32, f[1] as f32, f[2] as f32, f[3] as f32];
        let device = device_or_default(py, device)?;
        let camera = camera.inner.clone();
        let warper = py
            .detach(|| Warper::new(device.gpu(), &camera, &options))
            .py(py)?;
        Ok(PyWarper {
            source_camera: warper.source_camera().clone(),
            input_size: warper.input_size(),
            output_size: warper.output_size(),
            direction: match dir {
                WarpDirection::Distort => "distort",
                WarpDirection::Undistort => "undistort",
                WarpDirection::Precorrect => "precorrect",
            },
            method: m.to_string(),
            rgba8: Mutex::new(warper),
            rgba32f: Mutex::new(None),
            device,
            camera,
            options,
        })
    }

    /// The pinhole side's camera actually used (the input's for distort, the output's for
    /// undistort and precorrect).
    #[getter]
    fn source_camera(&self) -> PyCamera {
        PyCamera {
            inner: self.source_camera.clone(),
        }
    }
    /// The lens camera the warper was built for.
    #[getter]
    fn camera(&self) -> PyCamera {
        PyCamera {
            inner: self.camera.clone(),
        }
    }
    /// ``(width, height)`` of the images it takes.
    #[getter]
    fn input_size(&self) -> (u32, u32) {
        self.input_size
    }
    /// ``(width, height)`` of the images it returns.
    #[getter]
    fn output_size(&self) -> (u32, u32) {
        self.output_size
    }
    #[getter]
    fn direction(&self) -> &'static str {
        self.direction
    }
    #[getter]
    fn method(&self) -> &str {
        &self.method
    }
    /// ``"nearest"``, ``"bilinear"`` or ``"bicubic"``.
    #[getter]
    fn interpolation(&self) -> &'static str {
        self.options.sampling.name()
    }
    /// ``"constant"``, ``"replicate"`` or ``"reflect"``.
    #[getter]
    fn border(&self) -> &'static str {
        self.options.border.name()
    }
    #[getter]
    fn device(&self) -> PyDevice {
        PyDevice {
            inner: self.device.clone(),
        }
    }

    /// Warps ``image`` (``(H, W)`` or ``(H, W, 1|3|4)``; uint8, uint16 or float32) and returns a
    /// new array of the same dtype and channels, or writes ``out`` and returns it. With
    /// ``return_mask=True`` returns ``(out, mask)``, ``mask`` ``(H, W)`` bool, False where the
    /// pixel has no source in the valid domain.
    #[pyo3(signature = (image, out = None, return_mask = false))]
    fn __call__<'py>(
        &self,
        py: Python<'py>,
        image: &Bound<'py, PyAny>,
        out: Option<&Bound<'py, PyAny>>,
        return_mask: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        if let Ok(a) = image.cast::<PyArrayDyn<u8>>() {
            self.call_typed(py, a, out, return_mask)
        } else if let Ok(a) = image.cast::<PyArrayDyn<u16>>() {
            self.call_typed(py, a, out, return_mask)
        } else if let Ok(a) = image.cast::<PyArrayDyn<f32>>() {
            self.call_typed(py, a, out, return_mask)
        } else if image.cast::<PyArrayDyn<f64>>().is_ok() {
            self.call_f64(py, image, out, return_mask)
        } else if let Ok(a) = image.cast::<PyUntypedArray>() {
            Err(input(
                py,
                format!(
                    "image: dtype {} is not supported; expected uint8, uint16, float32 or float64 (convert it explicitly, e.g. image.astype(numpy.float32))",
                    a.dtype()
                ),
            ))
        } else {
            Err(input(
                py,
                format!(
                    "image: expected a numpy array, got {}",
                    image.get_type().name()?
                ),
            ))
        }
    }

    /// The warp's coordinate maps ``(map_x, map_y)``, each ``(H, W)`` float32, ready for
    /// ``cv2.remap``: per output pixel the source position its light comes from; NaN where it
    /// has none in the valid domain.
    fn maps<'py>(&self, py: Python<'py>) -> PyResult<(Map<'py>, Map<'py>)> {
        let maps = py.detach(|| lock(&self.rgba8).maps(&self.device)).py(py)?;
        let (w, h) = (self.output_size.0 as usize, self.output_size.1 as usize);
        let x: Vec<f32> = maps.iter().map(|m| m[0]).collect();
        let y: Vec<f32> = maps.iter().map(|m| m[1]).collect();
        Ok((
            PyArray1::from_vec(py, x).reshape([h, w])?,
            PyArray1::from_vec(py, y).reshape([h, w])?,
        ))
    }

    fn __repr__(&self) -> String {
        let (iw, ih) = self.input_size;
        let (ow, oh) = self.output_size;
        format!(
            "Warper({}, method={}, {iw}×{ih} → {ow}×{oh}, device={:?})",
            self.direction,
            self.method,
            self.device.name()
        )
    }
}

impl PyWarper {
    /// A float64 image: warped in float32 (the device's sample type) and handed back as
    /// float64, into `out` when given (a float64 array of the output's shape).
    fn call_f64<'py>(
        &self,
        py: Python<'py>,
        image: &Bound<'py, PyAny>,
        out: Option<&Bound<'py, PyAny>>,
        return_mask: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        if let Some(o) = out {
            if o.cast::<PyArrayDyn<f64>>().is_err() {
                return Err(input_arg(
                    py,
                    "out",
                    "a float64 image is warped into a float64 out= array",
                ));
            }
        }
        let single = image.call_method1("astype", ("float32",))?;
        let single = single
            .cast::<PyArrayDyn<f32>>()
            .map_err(|_| input_arg(py, "image", "expected a numpy array"))?;
        let warped = self.call_typed(py, single, None, return_mask)?;
        let (image_out, mask) = if return_mask {
            let (i, m): (Bound<'py, PyAny>, Bound<'py, PyAny>) = warped.extract()?;
            (i, Some(m))
        } else {
            (warped, None)
        };
        let double = match out {
            Some(o) => {
                let (want, got): (Vec<usize>, Vec<usize>) = (
                    image_out.getattr("shape")?.extract()?,
                    o.getattr("shape")?.extract()?,
                );
                if want != got {
                    return Err(input_arg(
                        py,
                        "out",
                        format!("shape {}; expected {}", tuple(&got), tuple(&want)),
                    ));
                }
                o.call_method1("__setitem__", (py.Ellipsis(), &image_out))
                    .map_err(|e| input_arg(py, "out", e))?;
                o.clone()
            }
            None => image_out.call_method1("astype", ("float64",))?,
        };
        match mask {
            Some(m) => Ok((double, m).into_pyobject(py)?.into_any()),
            None => Ok(double),
        }
    }

    fn call_typed<'py, T: Sample>(
        &self,
        py: Python<'py>,
        image: &Bound<'py, PyArrayDyn<T>>,
        out: Option<&Bound<'py, PyAny>>,
        return_mask: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let shape = image.shape().to_vec();
        let channels = match shape.as_slice() {
            [_, _] => 1,
            [_, _, c] if [1, 3, 4].contains(c) => *c,
            _ => {
                return Err(input(
                    py,
                    format!(
                        "image: shape {}; expected (H, W), (H, W, 1), (H, W, 3) or (H, W, 4)",
                        tuple(&shape)
                    ),
                ))
            }
        };
        let (iw, ih) = self.input_size;
        if (shape[0], shape[1]) != (ih as usize, iw as usize) {
            return Err(input(
                py,
                format!(
                    "image: (H, W) = ({}, {}), but this warper takes ({ih}, {iw}) (input_size {iw}×{ih})",
                    shape[0], shape[1]
                ),
            ));
        }
        let (ow, oh) = self.output_size;
        let mut dims = vec![oh as usize, ow as usize];
        if shape.len() == 3 {
            dims.push(channels);
        }
        let output = match out {
            Some(o) => {
                let o = o.cast::<PyArrayDyn<T>>().map_err(|_| {
                    input(
                        py,
                        format!(
                            "out: expected a numpy array of the image's dtype {}",
                            image.dtype()
                        ),
                    )
                })?;
                if o.shape() != dims.as_slice() {
                    return Err(input(
                        py,
                        format!("out: shape {}; expected {}", tuple(o.shape()), tuple(&dims)),
                    ));
                }
                if !o.is_c_contiguous() {
                    return Err(input(py, "out: must be C-contiguous"));
                }
                o.clone()
            }
            None => PyArrayDyn::<T>::zeros(py, IxDyn(&dims), false),
        };
        let mask =
            return_mask.then(|| PyArray2::<bool>::zeros(py, [oh as usize, ow as usize], false));

        let source = image.readonly();
        // C-contiguous input is read in place; any other layout is copied once.
        // (`as_slice` also takes Fortran order, which is not the layout the warp reads.)
        let copied: Vec<T>;
        let samples: &[T] = match source.as_slice() {
            Ok(s) if image.is_c_contiguous() => s,
            _ => {
                copied = source.as_array().iter().copied().collect();
                &copied
            }
        };
        let mut target = output
            .try_readwrite()
            .map_err(|e| input(py, format!("out: {e}")))?;
        let target = target
            .as_slice_mut()
            .map_err(|e| input(py, format!("out: {e}")))?;
        let mut mask_rw = mask.as_ref().map(|m| m.readwrite());
        let mask_slice = match mask_rw.as_mut() {
            Some(m) => Some(
                m.as_slice_mut()
                    .map_err(|e| input(py, format!("mask: {e}")))?,
            ),
            None => None,
        };
        let input_image = HostImage {
            width: iw,
            height: ih,
            channels: channels as u32,
            pixels: T::host(samples),
        };
        py.detach(|| {
            let mut output_image = HostImageMut {
                width: ow,
                height: oh,
                channels: channels as u32,
                pixels: T::host_mut(target),
            };
            if T::FLOAT {
                let mut guard = lock(&self.rgba32f);
                if guard.is_none() {
                    let mut options = self.options.clone();
                    options.format = PixelFormat::Rgba32F;
                    *guard = Some(Warper::new(self.device.gpu(), &self.camera, &options)?);
                }
                match guard.as_mut() {
                    Some(w) => {
                        w.run_host(&self.device, &input_image, &mut output_image, mask_slice)
                    }
                    None => Err(vklens::Error::internal("float warper missing")),
                }
            } else {
                lock(&self.rgba8).run_host(
                    &self.device,
                    &input_image,
                    &mut output_image,
                    mask_slice,
                )
            }
        })
        .py(py)?;
        drop(mask_rw);
        let output = output.into_any();
        match mask {
            Some(m) => Ok(PyTuple::new(py, [output, m.into_any()])?.into_any()),
            None => Ok(output),
        }
    }
}

/// The pinhole camera whose image covers every valid pixel of ``camera`` with ``density``
/// source pixels per output pixel at the principal point: the source camera a distort warp
/// needs so that a barrel lens gets its borders.
#[pyfunction]
#[pyo3(signature = (camera, density = 1.0))]
fn overscan(py: Python<'_>, camera: PyRef<'_, PyCamera>, density: f64) -> PyResult<PyCamera> {
    if density.is_nan() || density <= 0.0 || density.is_infinite() {
        return Err(input(
            py,
            format!("density: {density} must be a positive number"),
        ));
    }
    Ok(PyCamera {
        inner: vklens::overscan(&camera.inner, density).py(py)?,
    })
}

// ---------------------------------------------------------------------------------------------
// Stereo rectification

/// A row-major matrix as a float64 ndarray of its shape.
fn ndarray<'py, const R: usize, const C: usize>(
    py: Python<'py>,
    m: &[[f64; C]; R],
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_vec(py, m.iter().flatten().copied().collect()).reshape([R, C])
}

/// What ``vklens.stereo_rectify`` returns: ``cv2.stereoRectify``'s ``R1, R2, P1, P2, Q,
/// validPixROI1, validPixROI2``, and the two rectified pinhole cameras.
#[pyclass(name = "StereoRectification", module = "vklens", frozen)]
struct PyStereoRectification {
    inner: vklens::StereoRectification,
}

#[pymethods]
impl PyStereoRectification {
    /// The first camera's rectification rotation, ``(3, 3)`` float64.
    #[getter(R1)]
    fn r1<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        ndarray(py, &self.inner.r1)
    }
    /// The second camera's rectification rotation, ``(3, 3)`` float64.
    #[getter(R2)]
    fn r2<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        ndarray(py, &self.inner.r2)
    }
    /// The first rectified camera's projection, ``(3, 4)`` float64.
    #[getter(P1)]
    fn p1<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        ndarray(py, &self.inner.p1)
    }
    /// The second rectified camera's projection (its baseline times the focal length in the
    /// fourth column), ``(3, 4)`` float64.
    #[getter(P2)]
    fn p2<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        ndarray(py, &self.inner.p2)
    }
    /// The disparity-to-depth matrix (``cv2.reprojectImageTo3D``'s), ``(4, 4)`` float64.
    #[getter(Q)]
    fn q<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        ndarray(py, &self.inner.q)
    }
    /// ``(x, y, w, h)``: the first rectified image's valid pixels (the whole image for a
    /// fisheye pair).
    #[getter]
    fn roi1(&self) -> (u32, u32, u32, u32) {
        self.inner.roi1
    }
    /// ``(x, y, w, h)``: the second's.
    #[getter]
    fn roi2(&self) -> (u32, u32, u32, u32) {
        self.inner.roi2
    }
    /// The first rectified camera (pinhole, at the new size).
    #[getter]
    fn left(&self) -> PyCamera {
        PyCamera {
            inner: self.inner.left.clone(),
        }
    }
    /// The second rectified camera.
    #[getter]
    fn right(&self) -> PyCamera {
        PyCamera {
            inner: self.inner.right.clone(),
        }
    }
    /// Whether the baseline runs along the image columns (OpenCV's vertical stereo).
    #[getter]
    fn vertical(&self) -> bool {
        self.inner.vertical
    }
    /// The distance between the camera centres, in the units of ``T``.
    #[getter]
    fn baseline(&self) -> f64 {
        self.inner.baseline()
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "StereoRectification({}, baseline={}, f={}, size={}×{}, roi1={:?}, roi2={:?})",
            if s.vertical { "vertical" } else { "horizontal" },
            s.baseline(),
            s.p1[0][0],
            s.left.width,
            s.left.height,
            s.roi1,
            s.roi2
        )
    }
}

/// ``R`` as ``cv2.stereoRectify`` takes it: a 3×3 matrix, or a Rodrigues vector shaped
/// ``(3,)``, ``(3, 1)`` or ``(1, 3)``.
fn pair_rotation(py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<vklens::PairRotation> {
    let (data, shape) = numbers(py, value, "R")?;
    match shape.as_slice() {
        [3, 3] => Ok(vklens::PairRotation::Matrix(std::array::from_fn(|i| {
            std::array::from_fn(|j| data[i * 3 + j])
        }))),
        [3] | [3, 1] | [1, 3] => Ok(vklens::PairRotation::Rodrigues([data[0], data[1], data[2]])),
        _ => Err(input_arg(
            py,
            "R",
            format!(
                "shape {}; expected a rotation matrix (3, 3) or a Rodrigues vector (3,), (3, 1) or (1, 3)",
                tuple(&shape)
            ),
        )),
    }
}

/// The rectification of a calibrated pair, as ``cv2.stereoRectify(K1, D1, K2, D2, size, R, T,
/// flags, alpha, new_size)`` computes it for OpenCV's standard model and
/// ``cv2.fisheye.stereoRectify(..., flags, new_size, balance, fov_scale)`` for its fisheye
/// model. ``left`` is the first camera, ``right`` the second: X2 = R X1 + T.
#[pyfunction]
#[pyo3(signature = (left, right, R, T, *, alpha = None, new_size = None, zero_disparity = true, balance = 0.0, fov_scale = 1.0))]
#[allow(clippy::too_many_arguments, non_snake_case)]
fn stereo_rectify(
    py: Python<'_>,
    left: PyRef<'_, PyCamera>,
    right: PyRef<'_, PyCamera>,
    R: &Bound<'_, PyAny>,
    T: &Bound<'_, PyAny>,
    alpha: Option<f64>,
    new_size: Option<(i64, i64)>,
    zero_disparity: bool,
    balance: f64,
    fov_scale: f64,
) -> PyResult<PyStereoRectification> {
    let rotation = pair_rotation(py, R)?;
    let t = vector(py, T, "T", Some(3))?;
    let new_size = new_size
        .map(|s| Ok::<_, PyErr>((side(py, s.0, "new_size")?, side(py, s.1, "new_size")?)))
        .transpose()?;
    let options = vklens::StereoOptions {
        alpha,
        new_size,
        zero_disparity,
        balance,
        fov_scale,
    };
    let (a, b) = (&left.inner, &right.inner);
    let inner = py
        .detach(|| vklens::stereo_rectify(a, b, rotation, [t[0], t[1], t[2]], &options))
        .py(py)?;
    Ok(PyStereoRectification { inner })
}

// ---------------------------------------------------------------------------------------------
// Scenes

/// A Python value of a scene dict as TOML, keys in the dict's order (a `[classes]` table's
/// first matching pattern wins). `key` names it in errors.
fn toml_value(py: Python<'_>, v: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    if let Ok(d) = v.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, item) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| input(py, format!("scene: {key}: keys must be strings")))?;
            let inner = if key.is_empty() {
                k.clone()
            } else {
                format!("{key}.{k}")
            };
            table.insert(k, toml_value(py, &item, &inner)?);
        }
        return Ok(toml::Value::Table(table));
    }
    if let Ok(b) = v.cast::<pyo3::types::PyBool>() {
        return Ok(toml::Value::Boolean(b.is_true()));
    }
    if let Ok(i) = v.cast::<pyo3::types::PyInt>() {
        let i: i64 = i
            .extract()
            .map_err(|_| input(py, format!("scene: {key}: {i} does not fit 64 bits")))?;
        return Ok(toml::Value::Integer(i));
    }
    if let Ok(f) = v.cast::<pyo3::types::PyFloat>() {
        return Ok(toml::Value::Float(f.value()));
    }
    if let Ok(s) = v.cast::<pyo3::types::PyString>() {
        return Ok(toml::Value::String(s.extract::<String>()?));
    }
    if v.is_none() {
        return Err(input(
            py,
            format!("scene: {key}: TOML has no null: leave the key out"),
        ));
    }
    if let Ok(items) = v.try_iter() {
        let mut array = Vec::new();
        for (i, item) in items.enumerate() {
            array.push(toml_value(py, &item?, &format!("{key}[{i}]"))?);
        }
        return Ok(toml::Value::Array(array));
    }
    Err(input(
        py,
        format!(
            "scene: {key}: the dict must hold only tables, lists, strings, numbers and booleans, found {}",
            v.get_type().name()?
        ),
    ))
}

/// A dict of the scene file's tables as TOML text (the scene parser reads TOML).
fn scene_toml(py: Python<'_>, scene: &Bound<'_, PyAny>) -> PyResult<String> {
    let table = toml_value(py, scene, "")?;
    toml::to_string(&table).map_err(|e| input(py, format!("scene: {e}")))
}

/// Renders a scene file (a path) or the same tables as a dict: one dict per pose with the
/// outputs the scene asks for.
#[pyfunction]
#[pyo3(signature = (scene, device = None, base = None))]
fn render_scene<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    device: Option<PyRef<'py, PyDevice>>,
    base: Option<PathBuf>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let renderer = if scene.cast::<PyDict>().is_ok() {
        let text = scene_toml(py, scene)?;
        // Relative paths in the dict resolve against `base` (default: the working folder).
        let base = match base {
            Some(b) => b.join("scene.toml"),
            None => PathBuf::from("scene.toml"),
        };
        py.detach(|| SceneRenderer::parse(&text, &base)).py(py)?
    } else {
        let path: PathBuf = scene.extract().map_err(|_| {
            input(
                py,
                "scene: expected a path or a dict of the scene file's tables",
            )
        })?;
        py.detach(|| SceneRenderer::load(&path)).py(py)?
    };
    let device = device_or_default(py, device)?;
    let frames = py.detach(|| renderer.render_all(&device)).py(py)?;
    // One list of the scene's objects, shared by every frame's dict.
    let objects = PyList::empty(py);
    for o in renderer.objects() {
        let e = PyDict::new(py);
        e.set_item("id", o.id)?;
        e.set_item("name", &o.name)?;
        e.set_item("class", o.class)?;
        objects.append(e)?;
    }
    let objects = objects.unbind();
    let mut out = Vec::with_capacity(frames.len());
    for f in frames {
        let r = f.rendered;
        let (w, h) = (r.width as usize, r.height as usize);
        let d = PyDict::new(py);
        d.set_item("index", f.index)?;
        d.set_item("ms", f.ms)?;
        if let Some(c) = r.color {
            match c.pixels {
                Pixels::Rgba8(p) => d.set_item(
                    "color",
                    PyArray1::from_vec(py, p.into_iter().flatten().collect()).reshape([h, w, 4])?,
                )?,
                Pixels::Rgba32F(p) => d.set_item(
                    "color",
                    PyArray1::from_vec(py, p.into_iter().flatten().collect()).reshape([h, w, 4])?,
                )?,
                Pixels::R32Uint(p) => {
                    d.set_item("color", PyArray1::from_vec(py, p).reshape([h, w])?)?
                }
            }
        }
        if let Some(ids) = r.ids {
            d.set_item("ids", PyArray1::from_vec(py, ids).reshape([h, w])?)?;
        }
        if let Some(flow) = r.flow {
            let flat: Vec<f32> = flow.into_iter().flatten().collect();
            d.set_item("flow", PyArray1::from_vec(py, flat).reshape([h, w, 2])?)?;
        }
        if let Some(depth) = r.depth {
            d.set_item("depth", PyArray1::from_vec(py, depth).reshape([h, w])?)?;
        }
        if let Some(range) = r.range {
            d.set_item("range", PyArray1::from_vec(py, range).reshape([h, w])?)?;
        }
        let l = f.labels;
        if let Some(classes) = l.classes {
            let classes: Vec<u16> = classes.into_iter().map(|c| c as u16).collect();
            d.set_item("classes", PyArray1::from_vec(py, classes).reshape([h, w])?)?;
        }
        if let Some(boxes) = l.boxes {
            let list = PyList::empty(py);
            for b in boxes {
                let e = PyDict::new(py);
                e.set_item("id", b.id)?;
                e.set_item("name", b.name)?;
                e.set_item("class", b.class)?;
                e.set_item("visible_px", b.visible_px)?;
                e.set_item("bbox_visible", b.bbox_visible.to_vec())?;
                e.set_item("bbox_full", b.bbox_full.to_vec())?;
                let corners: Vec<Option<Vec<f64>>> =
                    b.corners_3d.iter().map(|c| c.map(|p| p.to_vec())).collect();
                e.set_item("corners_3d", corners)?;
                e.set_item("corners_visible", b.corners_visible.to_vec())?;
                list.append(e)?;
            }
            d.set_item("boxes", list)?;
        }
        if let Some(keypoints) = l.keypoints {
            let list = PyList::empty(py);
            for k in keypoints {
                let e = PyDict::new(py);
                e.set_item("name", k.name)?;
                e.set_item("pixel", k.pixel.map(|p| p.to_vec()))?;
                e.set_item("visible", k.visible)?;
                list.append(e)?;
            }
            d.set_item("keypoints", list)?;
        }
        d.set_item("objects", objects.clone_ref(py))?;
        out.push(d);
    }
    Ok(out)
}

#[pymodule]
fn _vklens(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyCamera>()?;
    m.add_class::<PyDevice>()?;
    m.add_class::<PyWarper>()?;
    m.add_class::<PyStereoRectification>()?;
    m.add_function(wrap_pyfunction!(stereo_rectify, m)?)?;
    m.add_function(wrap_pyfunction!(overscan, m)?)?;
    m.add_function(wrap_pyfunction!(render_scene, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
