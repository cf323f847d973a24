//! The C API of vklens: opaque handles over the crate's public surface (`Camera`, `Gpu` from
//! the caller's Vulkan, `Warper` recording into the caller's command buffer), errors as
//! handles, every entry point behind `catch_unwind`. `include/vklens.h` is generated from this
//! file by cbindgen; the conventions (ownership, threads, layouts) are in its preamble
//! (`cbindgen.toml`) and in the comments below, which become the header's.
//!
//! The shape follows librashader's C API: `*_create(..., out)` / `*_free(&handle)`, an error
//! handle that is NULL on success, and the caller's `vkGetInstanceProcAddr` to reach its
//! instance and device.

#![allow(non_camel_case_types)]
#![deny(unsafe_op_in_unsafe_fn)]
// Every pointer argument is checked for NULL before use; the remaining contract (pointers
// to as many elements as the count says, live handles) is the C caller's, stated per function.
#![allow(clippy::missing_safety_doc)]

use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr;
use std::sync::{Arc, Mutex};

use ash::vk;
use vklens_core::{
    Border, Camera, Device, EnabledFeatures, Error, ErrorKind, Frame, Gpu, ImageRef, PixelFormat,
    Pixels, Sampling, SceneRenderer, WarpMethod, WarpOptions, Warper,
};

/// The version of this header's structs: set every `version` field to it.
pub const VKL_API_VERSION: u32 = 1;

pub type VkInstance = vk::Instance;
pub type VkPhysicalDevice = vk::PhysicalDevice;
pub type VkDevice = vk::Device;
pub type VkQueue = vk::Queue;
pub type VkCommandBuffer = vk::CommandBuffer;
pub type VkImage = vk::Image;
pub type VkImageView = vk::ImageView;
pub type VkFormat = vk::Format;
pub type PFN_vkGetInstanceProcAddr = Option<vk::PFN_vkGetInstanceProcAddr>;

// ---------------------------------------------------------------------------------------------
// Errors

/// What kind of failure an error is, so that the caller can act on it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum vkl_error_kind {
    /// Not an error (what `vkl_error_kind_of(NULL)` returns).
    VKL_ERROR_NONE = 0,
    /// Bad input: an argument, file, key or value; the message names it. Fix the input.
    VKL_ERROR_INPUT = 1,
    /// The device lacks a feature or limit the work needs. Pick another device or a smaller job.
    VKL_ERROR_UNSUPPORTED,
    /// A Vulkan call failed (the message names it and its VkResult).
    VKL_ERROR_VULKAN,
    /// Reading or writing a file failed; the message names the path.
    VKL_ERROR_IO,
    /// A bug in vklens (a caught panic among them): please report the message.
    VKL_ERROR_INTERNAL,
}

/// An error: its kind, message, and the argument it is about (if one).
pub struct vkl_error_s {
    kind: vkl_error_kind,
    message: CString,
    argument: Option<CString>,
}

/// An error handle; NULL means success.
pub type vkl_error = *mut vkl_error_s;

fn error(kind: vkl_error_kind, message: String) -> vkl_error {
    let message = CString::new(message.replace('\0', " ")).unwrap_or_default();
    Box::into_raw(Box::new(vkl_error_s {
        kind,
        message,
        argument: None,
    }))
}

fn from_error(e: Error) -> vkl_error {
    let kind = match e.kind() {
        ErrorKind::Input => vkl_error_kind::VKL_ERROR_INPUT,
        ErrorKind::Unsupported => vkl_error_kind::VKL_ERROR_UNSUPPORTED,
        ErrorKind::Vulkan => vkl_error_kind::VKL_ERROR_VULKAN,
        ErrorKind::Io => vkl_error_kind::VKL_ERROR_IO,
        _ => vkl_error_kind::VKL_ERROR_INTERNAL,
    };
    let Some(argument) = e.argument_name() else {
        return error(kind, e.to_string());
    };
    // The C names: the options struct's fields.
    let c_name = match argument {
        "size" => "options.width, options.height",
        "camera_name" => "options.camera_name",
        "camera_index" => "options.camera_index",
        "method" => "options.method",
        "chromatic" => "options.chromatic",
        "source_camera" => "options.source_camera",
        "frames_in_flight" => "options.frames_in_flight",
        "rectification" => "options.rectification",
        other => other,
    };
    let handle = error(kind, format!("{}: {}", c_name, e.message_only()));
    // SAFETY: `error` returned a fresh, non-null box that nothing else holds yet.
    unsafe { (*handle).argument = CString::new(argument).ok() };
    handle
}

fn input(message: impl Into<String>) -> Error {
    Error::input(message.into())
}

/// Runs an entry point's body: its error, or a panic inside it, becomes an error handle.
fn guard(body: impl FnOnce() -> Result<(), Error>) -> vkl_error {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => ptr::null_mut(),
        Ok(Err(e)) => from_error(e),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            error(
                vkl_error_kind::VKL_ERROR_INTERNAL,
                format!("internal error (please report): {what}"),
            )
        }
    }
}

/// `p` as a reference, or an input error naming `what`.
///
/// # Safety
/// A non-null `p` must point to a live `T`.
unsafe fn arg<'a, T>(p: *const T, what: &str) -> Result<&'a T, Error> {
    // SAFETY: the caller guarantees a non-null `p` points to a live `T`.
    unsafe { p.as_ref() }.ok_or_else(|| input(format!("{what}: NULL pointer")))
}

/// Writes `value` to `*out`, which must not be NULL.
///
/// # Safety
/// A non-null `out` must point to writable memory for one `T`.
unsafe fn put<T>(out: *mut T, what: &str, value: T) -> Result<(), Error> {
    if out.is_null() {
        return Err(input(format!("{what}: NULL pointer")));
    }
    // SAFETY: non-null (checked) and writable (the caller's contract).
    unsafe { out.write(value) };
    Ok(())
}

/// Writes a `(width, height)` pair to `*width` and `*height`, neither of which may be NULL.
///
/// # Safety
/// Non-null pointers point to writable `u32`s.
unsafe fn put_size(width: *mut u32, height: *mut u32, size: (u32, u32)) -> Result<(), Error> {
    if height.is_null() {
        return Err(input("height: NULL pointer"));
    }
    // SAFETY: the caller's contract; `height` is checked non-null before `width` is written,
    // so an error leaves both untouched.
    unsafe {
        put(width, "width", size.0)?;
        put(height, "height", size.1)
    }
}

/// `n` elements at `p` (which may be NULL only when `n` is 0).
///
/// # Safety
/// A non-null `p` must point to `n` readable `T`s.
unsafe fn slice<'a, T>(p: *const T, n: usize, what: &str) -> Result<&'a [T], Error> {
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(input(format!("{what}: NULL pointer for {n} element(s)")));
    }
    // SAFETY: non-null and `n` readable elements (the caller's contract).
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

/// Frees a boxed handle and nulls it; NULL or an already nulled handle is harmless.
///
/// # Safety
/// A non-null `handle` must point to a handle that is NULL or came from this library's
/// `Box::into_raw` and was not freed through another copy.
unsafe fn free<T>(handle: *mut *mut T) {
    if handle.is_null() {
        return;
    }
    // SAFETY: the caller's contract (see above); the handle is nulled so that a second free
    // through the same variable sees NULL.
    unsafe {
        let inner = handle.replace(ptr::null_mut());
        if !inner.is_null() {
            drop(Box::from_raw(inner));
        }
    }
}

/// Runs a `*_free` body; a panic while dropping (a bug) must not unwind into C either.
fn release(body: impl FnOnce()) {
    let _ = catch_unwind(AssertUnwindSafe(body));
}

/// The kind of `e`; `VKL_ERROR_NONE` for NULL.
///
/// # Safety
/// `e` is NULL or an error this library returned and that was not freed.
#[no_mangle]
pub unsafe extern "C" fn vkl_error_kind_of(e: vkl_error) -> vkl_error_kind {
    // SAFETY: the caller's contract: NULL or a live error.
    unsafe { e.as_ref() }.map_or(vkl_error_kind::VKL_ERROR_NONE, |e| e.kind)
}

/// The message of `e` (UTF-8, NUL-terminated), valid until `vkl_error_free`; `""` for NULL.
///
/// # Safety
/// `e` is NULL or an error this library returned and that was not freed.
#[no_mangle]
pub unsafe extern "C" fn vkl_error_message(e: vkl_error) -> *const c_char {
    // SAFETY: the caller's contract: NULL or a live error.
    match unsafe { e.as_ref() } {
        Some(e) => e.message.as_ptr(),
        None => c"".as_ptr(),
    }
}

/// The argument an VKL_ERROR_INPUT error is about, in the library's words ("method",
/// "source_camera", "chromatic", "size", "camera_name", …), or NULL when it is not about one
/// argument (or `e` is NULL). Valid until the error is freed.
///
/// # Safety
/// `e` is NULL or an error this library returned and has not freed.
#[no_mangle]
pub unsafe extern "C" fn vkl_error_argument(e: vkl_error) -> *const c_char {
    // SAFETY: the caller's contract: NULL or a live error.
    match unsafe { e.as_ref() }.and_then(|e| e.argument.as_ref()) {
        Some(a) => a.as_ptr(),
        None => ptr::null(),
    }
}

/// Frees an error and sets `*e` to NULL. `e == NULL` and `*e == NULL` are harmless.
///
/// # Safety
/// `e` is NULL or points to NULL or to an error this library returned.
#[no_mangle]
pub unsafe extern "C" fn vkl_error_free(e: *mut vkl_error) {
    // SAFETY: the caller's contract, as `free` needs it.
    release(|| unsafe { free(e) })
}

// ---------------------------------------------------------------------------------------------
// Cameras

/// A calibrated camera (OpenCV's standard model, or a Brown lens held as its exact twin).
pub struct vkl_camera_s {
    camera: Camera,
}

/// A camera handle. Immutable: safe to use from any thread.
pub type vkl_camera = *mut vkl_camera_s;

fn new_camera(out: *mut vkl_camera, camera: Camera) -> Result<(), Error> {
    let handle = Box::into_raw(Box::new(vkl_camera_s { camera }));
    // SAFETY: `out` was checked non-null by the caller of `new_camera`, and is writable (the
    // C caller's contract).
    unsafe { out.write(handle) };
    Ok(())
}

/// Reads any camera file the command line reads (vklens JSON, OpenCV FileStorage YAML / XML /
/// JSON, ROS camera_info YAML, a Brown lens). A missing or unreadable file is VKL_ERROR_IO, a
/// malformed one VKL_ERROR_INPUT; both name the file. No Vulkan needed.
///
/// # Safety
/// `path` is NULL or a NUL-terminated string; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_camera_load(path: *const c_char, out: *mut vkl_camera) -> vkl_error {
    // SAFETY: the caller's contract is vkl_camera_load_ex's with NULL options.
    unsafe { vkl_camera_load_ex(path, ptr::null(), out) }
}

/// Which camera of a file to load, and the image size for a file that gives none (what the
/// command line's --camera-index, --camera-name and --size say).
#[repr(C)]
pub struct vkl_load_options {
    /// VKL_API_VERSION.
    pub version: u32,
    /// 0-based position in the file; -1 = not given (the first, unless `camera_name` says).
    pub camera_index: i64,
    /// NULL = not given; else the camera's name as the file writes it ("cam1", "M2", "LEFT",
    /// a COLMAP camera id).
    pub camera_name: *const c_char,
    /// 0 = not given; else the image size of a file that has none (where the file gives one,
    /// they must agree).
    pub width: u32,
    pub height: u32,
}

/// vkl_camera_load with options: a camera of a file that holds several, by index or name, and
/// the image size of a file that has none. `options` NULL is vkl_camera_load. Errors as
/// vkl_camera_load's; an unknown name or index is VKL_ERROR_INPUT and lists the file's cameras.
///
/// # Safety
/// `path` is NULL or a NUL-terminated string; `options` is NULL or points to a
/// vkl_load_options whose `camera_name` is NULL or NUL-terminated; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_camera_load_ex(
    path: *const c_char,
    options: *const vkl_load_options,
    out: *mut vkl_camera,
) -> vkl_error {
    guard(|| {
        if out.is_null() {
            return Err(input("out: NULL pointer"));
        }
        if path.is_null() {
            return Err(input("path: NULL pointer"));
        }
        // SAFETY: non-null and NUL-terminated (the caller's contract).
        let path = unsafe { CStr::from_ptr(path) }
            .to_str()
            .map_err(|_| input("path: not UTF-8"))?;
        let mut load = vklens_core::LoadOptions::default();
        // SAFETY: NULL or a readable vkl_load_options (the caller's contract).
        if let Some(o) = unsafe { options.as_ref() } {
            if o.version != VKL_API_VERSION {
                return Err(input(format!(
                    "options.version: {} (expected VKL_API_VERSION = {VKL_API_VERSION})",
                    o.version
                )));
            }
            load.index = match o.camera_index {
                -1 => None,
                i => Some(usize::try_from(i).map_err(|_| {
                    input(format!(
                        "options.camera_index: {i} (a camera's 0-based position, or -1)"
                    ))
                })?),
            };
            if !o.camera_name.is_null() {
                // SAFETY: non-null and NUL-terminated (the caller's contract).
                let name = unsafe { CStr::from_ptr(o.camera_name) }
                    .to_str()
                    .map_err(|_| input("options.camera_name: not UTF-8"))?;
                load.name = Some(name.to_string());
            }
            load.size = match (o.width, o.height) {
                (0, 0) => None,
                (w, h) if w > 0 && h > 0 => Some((w, h)),
                (w, h) => {
                    return Err(input(format!(
                        "options.width, options.height: {w}×{h} (both 0 for none, or both positive)"
                    )))
                }
            };
        }
        new_camera(out, Camera::load_with(path, &load)?)
    })
}

/// Builds a camera from OpenCV's camera matrix `K` (9 doubles, row-major as OpenCV stores
/// it: fx 0 cx / 0 fy cy / 0 0 1), its distortion vector (`count` = 4, 5, 8, 12 or 14
/// coefficients in OpenCV's order; `dist_coeffs` may be NULL with `count` 0 for none) and the
/// image size. No Vulkan needed.
///
/// # Safety
/// `K` is NULL or points to 9 doubles; `dist_coeffs` is NULL or points to `count` doubles;
/// `out` is NULL or writable.
#[no_mangle]
#[allow(non_snake_case)] // `K`, as OpenCV and the header name it
pub unsafe extern "C" fn vkl_camera_from_opencv(
    width: u32,
    height: u32,
    K: *const f64,
    dist_coeffs: *const f64,
    count: usize,
    out: *mut vkl_camera,
) -> vkl_error {
    guard(|| {
        if out.is_null() {
            return Err(input("out: NULL pointer"));
        }
        if K.is_null() {
            return Err(input("K: NULL pointer"));
        }
        // SAFETY: 9 readable doubles (the caller's contract).
        let k = unsafe { slice(K, 9, "K")? };
        // SAFETY: `count` readable doubles (the caller's contract).
        let d = unsafe { slice(dist_coeffs, count, "dist_coeffs")? };
        let d: &[f64] = if d.is_empty() { &[0.0; 5] } else { d };
        let km = [[k[0], k[1], k[2]], [k[3], k[4], k[5]], [k[6], k[7], k[8]]];
        // The library names the argument (`K`, `dist_coeffs`, `size`); the size is this
        // function's `width, height`.
        let camera =
            Camera::from_opencv(km, d, (width, height)).map_err(|e| match e.argument_name() {
                Some("size") => Error::argument("width, height", e.message_only()),
                _ => e,
            })?;
        new_camera(out, camera)
    })
}

/// `(width, height)` of the camera's images.
///
/// # Safety
/// `c` is NULL or a live camera; `width` and `height` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_camera_size(
    c: vkl_camera,
    width: *mut u32,
    height: *mut u32,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live camera (the caller's contract).
        let c = unsafe { arg(c, "camera")? };
        // SAFETY: NULL (refused) or writable (the caller's contract).
        unsafe { put_size(width, height, (c.camera.width, c.camera.height)) }
    })
}

/// The forward model, exact in f64 as cv2.projectPoints: `n` normalized undistorted points
/// `xy` (x = X/Z, y = Y/Z; 2n doubles) to `n` distorted pixels `uv_out` (2n doubles). A pair
/// of NaN where the model is undefined (a rational denominator vanishes, a non-finite input).
///
/// # Safety
/// `c` is NULL or a live camera; `xy` and `uv_out` are NULL or point to 2n doubles (they may
/// be the same array).
#[no_mangle]
pub unsafe extern "C" fn vkl_camera_distort_points(
    c: vkl_camera,
    xy: *const f64,
    n: usize,
    uv_out: *mut f64,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live camera (the caller's contract).
        let c = unsafe { arg(c, "camera")? };
        // SAFETY: 2n readable and writable doubles (the caller's contract).
        let points = unsafe { pairs(xy, n, "xy", uv_out, "uv_out")? };
        let result = c.camera.distort_points(&points);
        // SAFETY: as above.
        unsafe { write_pairs(uv_out, &result) };
        Ok(())
    })
}

/// The inverse model: `n` distorted pixels `uv` (2n doubles) to normalized undistorted points
/// `xy_out` (2n doubles) with Newton's method; a pair of NaN outside the valid domain (the lens
/// folds over there, or the pixel has no preimage).
///
/// # Safety
/// `c` is NULL or a live camera; `uv` and `xy_out` are NULL or point to 2n doubles (they may
/// be the same array).
#[no_mangle]
pub unsafe extern "C" fn vkl_camera_undistort_points(
    c: vkl_camera,
    uv: *const f64,
    n: usize,
    xy_out: *mut f64,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live camera (the caller's contract).
        let c = unsafe { arg(c, "camera")? };
        // SAFETY: 2n readable and writable doubles (the caller's contract).
        let points = unsafe { pairs(uv, n, "uv", xy_out, "xy_out")? };
        let result = c
            .camera
            .undistort_points(&points, vklens_core::InverseMethod::Newton);
        // SAFETY: as above.
        unsafe { write_pairs(xy_out, &result) };
        Ok(())
    })
}

/// Copies `n` pairs in (so that in and out may alias), checking both pointers.
///
/// # Safety
/// Non-null pointers point to 2n doubles.
unsafe fn pairs(
    input_ptr: *const f64,
    n: usize,
    in_name: &str,
    out: *mut f64,
    out_name: &str,
) -> Result<Vec<[f64; 2]>, Error> {
    let count = n
        .checked_mul(2)
        .ok_or_else(|| input(format!("n: {n} points is too many")))?;
    if n > 0 && out.is_null() {
        return Err(input(format!("{out_name}: NULL pointer for {n} point(s)")));
    }
    // SAFETY: 2n readable doubles (the caller's contract).
    let flat = unsafe { slice(input_ptr, count, in_name)? };
    Ok(flat.chunks_exact(2).map(|p| [p[0], p[1]]).collect())
}

/// # Safety
/// `out` points to `2 * values.len()` writable doubles (non-null when `values` is not empty).
unsafe fn write_pairs(out: *mut f64, values: &[Option<[f64; 2]>]) {
    for (i, v) in values.iter().enumerate() {
        let [a, b] = v.unwrap_or([f64::NAN; 2]);
        // SAFETY: in bounds of the 2n doubles the caller provides.
        unsafe {
            out.add(2 * i).write(a);
            out.add(2 * i + 1).write(b);
        }
    }
}

/// The camera's model as camera files name it: `brown` for a Brown headset lens, else one of
/// the names `vkl_model_name` lists (`opencv`, `opencv_fisheye`, `double_sphere`, ...). A
/// static NUL-terminated string the caller never frees; NULL for a NULL camera.
///
/// # Safety
/// `c` is NULL or a live camera.
#[no_mangle]
pub unsafe extern "C" fn vkl_camera_model(c: vkl_camera) -> *const c_char {
    // SAFETY: NULL or a live camera (the caller's contract).
    let Ok(c) = (unsafe { arg(c, "camera") }) else {
        return ptr::null();
    };
    c_name(c.camera.model_name()).map_or(ptr::null(), CStr::as_ptr)
}

/// `name` as a NUL-terminated string that lives as long as the process: the library's own
/// name for the model, so that no list here can fall behind the library's models. Each
/// distinct name is allocated once (there are as many as there are models).
/// The name of the `index`-th camera model vklens knows (0: `opencv`, OpenCV's standard model),
/// as camera files and `vkl_camera_model` spell it; NULL past the last. The list is the
/// library's own model list, in its order, which only ever grows at the end. A static
/// NUL-terminated string the caller never frees.
#[no_mangle]
pub extern "C" fn vkl_model_name(index: usize) -> *const c_char {
    catch_unwind(|| {
        vklens_core::camera_models()
            .get(index)
            .and_then(|name| c_name(name))
            .map_or(ptr::null(), CStr::as_ptr)
    })
    .unwrap_or(ptr::null())
}

fn c_name(name: &'static str) -> Option<&'static CStr> {
    static NAMES: Mutex<Vec<(&'static str, &'static CStr)>> = Mutex::new(Vec::new());
    let mut names = NAMES.lock().ok()?;
    if let Some((_, c)) = names.iter().find(|(n, _)| *n == name) {
        return Some(c);
    }
    let c: &'static CStr = Box::leak(CString::new(name).ok()?.into_boxed_c_str());
    names.push((name, c));
    Some(c)
}

/// Camera-frame points (X, Y, Z; 3n doubles, OpenCV's frame) to distorted pixels (2n
/// doubles), exact in f64; a pair of NaN where the model does not see the point (behind the
/// image plane for the standard model, outside the domain for the others, which see past 90°).
///
/// # Safety
/// `c` is NULL or a live camera; `xyz` is NULL or points to 3n doubles and `uv_out` to 2n
/// writable doubles that do not overlap them.
#[no_mangle]
pub unsafe extern "C" fn vkl_camera_project_points(
    c: vkl_camera,
    xyz: *const f64,
    n: usize,
    uv_out: *mut f64,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live camera (the caller's contract).
        let c = unsafe { arg(c, "camera")? };
        let count = n
            .checked_mul(3)
            .ok_or_else(|| input(format!("n: {n} points is too many")))?;
        if n > 0 && uv_out.is_null() {
            return Err(input(format!("uv_out: NULL pointer for {n} point(s)")));
        }
        // SAFETY: 3n readable doubles (the caller's contract).
        let flat = unsafe { slice(xyz, count, "xyz")? };
        let points: Vec<[f64; 3]> = flat.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
        let result = c.camera.project_points(&points);
        // SAFETY: 2n writable doubles (the caller's contract).
        unsafe { write_pairs(uv_out, &result) };
        Ok(())
    })
}

/// Distorted pixels (2n doubles) to unit camera-frame rays (3n doubles), past 90° where the
/// model sees there; a triple of NaN outside the valid domain.
///
/// # Safety
/// `c` is NULL or a live camera; `uv` is NULL or points to 2n doubles and `rays_out` to 3n
/// writable doubles that do not overlap them.
#[no_mangle]
pub unsafe extern "C" fn vkl_camera_unproject_points(
    c: vkl_camera,
    uv: *const f64,
    n: usize,
    rays_out: *mut f64,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live camera (the caller's contract).
        let c = unsafe { arg(c, "camera")? };
        // 3n doubles out: 2n in cannot overflow once 3n does not.
        n.checked_mul(3)
            .ok_or_else(|| input(format!("n: {n} points is too many")))?;
        if n > 0 && rays_out.is_null() {
            return Err(input(format!("rays_out: NULL pointer for {n} point(s)")));
        }
        // SAFETY: 2n readable doubles (the caller's contract; 2n ≤ 3n, which did not overflow).
        let flat = unsafe { slice(uv, 2 * n, "uv")? };
        let pixels: Vec<[f64; 2]> = flat.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
        let rays = c.camera.unproject_points(&pixels);
        for (i, r) in rays.iter().enumerate() {
            let r = r.unwrap_or([f64::NAN; 3]);
            for (j, v) in r.into_iter().enumerate() {
                // SAFETY: in bounds of the 3n doubles the caller provides.
                unsafe { rays_out.add(3 * i + j).write(v) };
            }
        }
        Ok(())
    })
}

/// Frees a camera and sets `*c` to NULL; warpers built from it keep their own copy.
///
/// # Safety
/// `c` is NULL or points to NULL or to a camera this library returned.
#[no_mangle]
pub unsafe extern "C" fn vkl_camera_free(c: *mut vkl_camera) {
    // SAFETY: the caller's contract, as `free` needs it.
    release(|| unsafe { free(c) })
}

// ---------------------------------------------------------------------------------------------
// The caller's Vulkan

/// The caller's Vulkan objects. vklens creates no instance and no device here and never
/// destroys these; they must outlive the vkl_gpu and every warper made from it.
///
/// The device must support compute on `queue_family_index` and have been created with the
/// `shaderStorageImageExtendedFormats` feature (the mask is an R8 storage image). `queue` is
/// only used to identify the family: vklens never submits to it.
#[repr(C)]
pub struct vkl_vulkan {
    /// VKL_API_VERSION.
    pub version: u32,
    pub instance: VkInstance,
    pub physical_device: VkPhysicalDevice,
    pub device: VkDevice,
    pub queue: VkQueue,
    pub queue_family_index: u32,
    /// The loader's (or the caller's) vkGetInstanceProcAddr: every Vulkan function vklens
    /// calls is looked up through it, for this instance and device.
    pub get_instance_proc_addr: PFN_vkGetInstanceProcAddr,
}

/// vklens's view of the caller's device: its function tables and its own memory allocator.
pub struct vkl_gpu_s {
    gpu: Gpu,
}

/// A GPU handle, made from the caller's Vulkan by vkl_gpu_create.
pub type vkl_gpu = *mut vkl_gpu_s;

/// Wraps the caller's Vulkan. Fails with VKL_ERROR_INPUT for a NULL or wrong-version `vk`, a
/// NULL handle or `get_instance_proc_addr`, or a queue family that does not exist.
///
/// # Safety
/// `vk` is NULL or points to a `vkl_vulkan` whose handles are live and belong together
/// (device of the physical device of the instance, queue of the family of the device);
/// `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_gpu_create(vk: *const vkl_vulkan, out: *mut vkl_gpu) -> vkl_error {
    guard(|| {
        if out.is_null() {
            return Err(input("out: NULL pointer"));
        }
        // SAFETY: NULL or a live `vkl_vulkan` (the caller's contract).
        let v = unsafe { arg(vk, "vk")? };
        if v.version != VKL_API_VERSION {
            return Err(input(format!(
                "vk.version: {} (expected VKL_API_VERSION = {VKL_API_VERSION})",
                v.version
            )));
        }
        let gipa = v
            .get_instance_proc_addr
            .ok_or_else(|| input("vk.get_instance_proc_addr: NULL"))?;
        for (name, null) in [
            ("vk.instance", v.instance == vk::Instance::null()),
            (
                "vk.physical_device",
                v.physical_device == vk::PhysicalDevice::null(),
            ),
            ("vk.device", v.device == vk::Device::null()),
            ("vk.queue", v.queue == vk::Queue::null()),
        ] {
            if null {
                return Err(input(format!("{name}: VK_NULL_HANDLE")));
            }
        }
        // SAFETY: `gipa` is a vkGetInstanceProcAddr (the caller's contract), `instance` is
        // live and `gipa` resolves its functions; `device` was created from it, so the
        // instance's vkGetDeviceProcAddr resolves the device's.
        let (instance, device) = unsafe {
            let entry = ash::Entry::from_static_fn(ash::StaticFn {
                get_instance_proc_addr: gipa,
            });
            let instance = ash::Instance::load(entry.static_fn(), v.instance);
            let device = ash::Device::load(instance.fp_v1_0(), v.device);
            (instance, device)
        };
        let allocator =
            gpu_allocator::vulkan::Allocator::new(&gpu_allocator::vulkan::AllocatorCreateDesc {
                instance: instance.clone(),
                device: device.clone(),
                physical_device: v.physical_device,
                debug_settings: Default::default(),
                buffer_device_address: false,
                allocation_sizes: Default::default(),
            })
            .map_err(|e| Error::internal(format!("the memory allocator: {e}")))?;
        // SAFETY: the handles belong together (the caller's contract), the allocator was just
        // made for this device, and no optional feature is claimed.
        let gpu = unsafe {
            Gpu::from_caller(
                &instance,
                v.physical_device,
                device,
                v.queue,
                v.queue_family_index,
                Arc::new(Mutex::new(allocator)),
                EnabledFeatures::default(),
            )?
        };
        let handle = Box::into_raw(Box::new(vkl_gpu_s { gpu }));
        // SAFETY: non-null (checked) and writable (the caller's contract).
        unsafe { out.write(handle) };
        Ok(())
    })
}

/// Frees vklens's view of the device (its allocator's memory goes back to the device) and
/// sets `*g` to NULL. The caller's objects are untouched. Warpers made from it stay usable
/// (they hold their own reference); the device must outlive all of them.
///
/// # Safety
/// `g` is NULL or points to NULL or to a gpu this library returned.
#[no_mangle]
pub unsafe extern "C" fn vkl_gpu_free(g: *mut vkl_gpu) {
    // SAFETY: the caller's contract, as `free` needs it.
    release(|| unsafe { free(g) })
}

// ---------------------------------------------------------------------------------------------
// The warp

/// Which way an image goes through the lens.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum vkl_direction {
    /// A pinhole image in, the lens image out (the inverse model per output pixel).
    VKL_DISTORT = 0,
    /// A lens image in, a pinhole image out (as cv2.initUndistortRectifyMap + cv2.remap).
    VKL_UNDISTORT,
    /// A headset pre-correction: the screen shows what the lens will undo.
    VKL_PRECORRECT,
}

/// What a warper is built for. NULL options are the defaults: distort, "lut", no chromatic
/// aberration, the camera's own intrinsics, R8G8B8A8_UNORM, transparent black fill.
#[repr(C)]
pub struct vkl_warp_options {
    /// VKL_API_VERSION.
    pub version: u32,
    pub direction: vkl_direction,
    /// NULL = "lut" (a map built once by vkl_warper_record_prepare); else as the command
    /// line's --method: "lut", "newton", "heikkila" or "fixed-point:N".
    pub method: *const c_char,
    /// NULL, or 3 magnifications R, G, B about the principal point (lateral chromatic
    /// aberration).
    pub chromatic: *const f64,
    /// NULL = the camera's own intrinsics and size; else the pinhole side's camera (for
    /// distort the source's, for undistort and precorrect the output's), without distortion.
    pub source_camera: vkl_camera,
    /// VK_FORMAT_R8G8B8A8_UNORM (also for 0, VK_FORMAT_UNDEFINED) or
    /// VK_FORMAT_R32G32B32A32_SFLOAT: the format of the source and output images.
    pub format: VkFormat,
    /// R, G, B, A in 0..1 for output pixels with no source.
    pub fill: [f32; 4],
    /// Frames vkl_warper_record may have in flight at once, 1 to 8 (0 = 2): the warper keeps
    /// one descriptor set per frame, so frame N + 1 may be recorded, with other images, while
    /// frame N still executes.
    pub frames_in_flight: u32,
    /// NULL, or 9 numbers: undistort and precorrect only, the rectification rotation R
    /// (row-major, OpenCV's R of initUndistortRectifyMap(K, D, R, P), a ROS camera_info's R);
    /// with source_camera as P's camera, a stereo pair's rectified view.
    pub rectification: *const f64,
    /// NULL = "bilinear"; else "nearest", "bilinear" or "bicubic" (cv2.remap's INTER_NEAREST,
    /// INTER_LINEAR, INTER_CUBIC).
    pub interpolation: *const c_char,
    /// NULL = "constant"; else what a source position off the source image reads, as
    /// cv2.remap's borders: "constant" (the fill), "replicate" (the edge pixel repeats) or
    /// "reflect" (the image mirrors, edge pixel included).
    pub border: *const c_char,
}

/// One of the caller's images: a 2D image with one mip level and layer, a view of it, and its
/// size.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct vkl_image {
    pub image: VkImage,
    pub view: VkImageView,
    pub width: u32,
    pub height: u32,
}

/// A warp built once (pipelines, map images) and recorded every frame.
pub struct vkl_warper_s {
    warper: Warper,
}

/// A warper handle: one thread at a time.
pub type vkl_warper = *mut vkl_warper_s;

/// Reads the options through raw field reads: `direction` is a C enum whose value is not
/// trusted, so no reference to the struct (with a possibly invalid enum inside) is formed.
///
/// # Safety
/// `o` points to a readable `vkl_warp_options` whose pointers are NULL or valid.
unsafe fn read_options(o: *const vkl_warp_options) -> Result<WarpOptions, Error> {
    // SAFETY: `o` is readable (the caller's contract); every read is of a plain field through
    // a raw pointer, and `direction` is read as the u32 it is stored as.
    let (version, direction, method, chromatic, source, format, fill, frames, rectification) = unsafe {
        (
            ptr::addr_of!((*o).version).read(),
            ptr::addr_of!((*o).direction).cast::<u32>().read(),
            ptr::addr_of!((*o).method).read(),
            ptr::addr_of!((*o).chromatic).read(),
            ptr::addr_of!((*o).source_camera).read(),
            ptr::addr_of!((*o).format).read(),
            ptr::addr_of!((*o).fill).read(),
            ptr::addr_of!((*o).frames_in_flight).read(),
            ptr::addr_of!((*o).rectification).read(),
        )
    };
    // SAFETY: as above.
    let (interpolation, border) = unsafe {
        (
            ptr::addr_of!((*o).interpolation).read(),
            ptr::addr_of!((*o).border).read(),
        )
    };
    if version != VKL_API_VERSION {
        return Err(input(format!(
            "options.version: {version} (expected VKL_API_VERSION = {VKL_API_VERSION})"
        )));
    }
    let mut options = match direction {
        0 => WarpOptions::distort(),
        1 => WarpOptions::undistort(),
        2 => WarpOptions::precorrect(),
        d => {
            return Err(input(format!(
                "options.direction: {d} (expected VKL_DISTORT, VKL_UNDISTORT or VKL_PRECORRECT)"
            )))
        }
    };
    // SAFETY (each): NULL or NUL-terminated (the caller's contract).
    if let Some(m) = unsafe { option_str(method, "options.method")? } {
        options.method = m
            .parse::<WarpMethod>()
            .map_err(|e| input(format!("options.method: {e}")))?;
    }
    if let Some(i) = unsafe { option_str(interpolation, "options.interpolation")? } {
        options.sampling = i
            .parse::<Sampling>()
            .map_err(|e| input(format!("options.interpolation: {e}")))?;
    }
    if let Some(b) = unsafe { option_str(border, "options.border")? } {
        options.border = b
            .parse::<Border>()
            .map_err(|e| input(format!("options.border: {e}")))?;
    }
    if !chromatic.is_null() {
        // SAFETY: 3 readable doubles (the caller's contract).
        let c = unsafe { slice(chromatic, 3, "options.chromatic")? };
        options.chromatic = Some([c[0], c[1], c[2]]);
    }
    // SAFETY: NULL or a live camera (the caller's contract).
    if let Some(s) = unsafe { source.as_ref() } {
        options.source_camera = Some(s.camera.clone());
    }
    options.format = match format {
        vk::Format::UNDEFINED | vk::Format::R8G8B8A8_UNORM => PixelFormat::Rgba8,
        vk::Format::R32G32B32A32_SFLOAT => PixelFormat::Rgba32F,
        f => {
            return Err(input(format!(
                "options.format: {f:?} (expected VK_FORMAT_R8G8B8A8_UNORM or VK_FORMAT_R32G32B32A32_SFLOAT)"
            )))
        }
    };
    if fill.iter().any(|v| !v.is_finite()) {
        return Err(input("options.fill: every value must be a finite number"));
    }
    options.fill = fill;
    if frames != 0 {
        options.frames_in_flight = frames as usize;
    }
    if !rectification.is_null() {
        // SAFETY: 9 readable doubles (the caller's contract).
        let r = unsafe { slice(rectification, 9, "options.rectification")? };
        options.rectification = Some(std::array::from_fn(|i| {
            std::array::from_fn(|j| r[3 * i + j])
        }));
    }
    Ok(options)
}

/// An options string: `None` for NULL.
///
/// # Safety
/// `p` is NULL or NUL-terminated.
unsafe fn option_str<'a>(p: *const c_char, name: &str) -> Result<Option<&'a str>, Error> {
    if p.is_null() {
        return Ok(None);
    }
    // SAFETY: non-null and NUL-terminated (the caller's contract).
    let s = unsafe { CStr::from_ptr(p) };
    s.to_str()
        .map(Some)
        .map_err(|_| input(format!("{name}: not UTF-8")))
}

/// Builds a warper: its pipelines, and for "lut" its map images (filled on the GPU by
/// vkl_warper_record_prepare). Records nothing.
///
/// # Safety
/// `g` and `c` are NULL or live handles; `o` is NULL or a readable `vkl_warp_options`; `out`
/// is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_warper_create(
    g: vkl_gpu,
    c: vkl_camera,
    o: *const vkl_warp_options,
    out: *mut vkl_warper,
) -> vkl_error {
    guard(|| {
        if out.is_null() {
            return Err(input("out: NULL pointer"));
        }
        // SAFETY: NULL or live handles (the caller's contract).
        let (g, c) = unsafe { (arg(g, "gpu")?, arg(c, "camera")?) };
        let options = if o.is_null() {
            WarpOptions::distort()
        } else {
            // SAFETY: a readable options struct (the caller's contract).
            unsafe { read_options(o)? }
        };
        let warper = Warper::new(&g.gpu, &c.camera, &options)?;
        let handle = Box::into_raw(Box::new(vkl_warper_s { warper }));
        // SAFETY: non-null (checked) and writable (the caller's contract).
        unsafe { out.write(handle) };
        Ok(())
    })
}

/// `(width, height)` of the source image vkl_warper_record takes.
///
/// # Safety
/// `w` is NULL or a live warper; `width` and `height` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_warper_source_size(
    w: vkl_warper,
    width: *mut u32,
    height: *mut u32,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live warper (the caller's contract).
        let w = unsafe { arg(w, "warper")? };
        // SAFETY: NULL (refused) or writable (the caller's contract).
        unsafe { put_size(width, height, w.warper.input_size()) }
    })
}

/// `(width, height)` of the output (and mask) image vkl_warper_record writes.
///
/// # Safety
/// `w` is NULL or a live warper; `width` and `height` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_warper_output_size(
    w: vkl_warper,
    width: *mut u32,
    height: *mut u32,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live warper (the caller's contract).
        let w = unsafe { arg(w, "warper")? };
        // SAFETY: NULL (refused) or writable (the caller's contract).
        unsafe { put_size(width, height, w.warper.output_size()) }
    })
}

/// Records the one-off work, once, before the first vkl_warper_record: for "lut" the map
/// build (compute dispatches writing the warper's own map images), and the layout
/// transitions of its own images, followed by a COMPUTE_SHADER → COMPUTE_SHADER barrier
/// (SHADER_WRITE → SHADER_READ) so that the warp reads finished maps. None of the caller's
/// images is touched.
///
/// Never submits, never waits. `cmd` must be a primary or secondary command buffer in the
/// recording state, outside a render pass, on a queue family with compute; it changes the
/// bound compute pipeline and descriptor sets. Not again while that work is pending.
///
/// # Safety
/// `w` is NULL or a live warper; `cmd` is recording as stated.
#[no_mangle]
pub unsafe extern "C" fn vkl_warper_record_prepare(
    w: vkl_warper,
    cmd: VkCommandBuffer,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live warper (the caller's contract).
        let w = unsafe { arg(w, "warper")? };
        if cmd == vk::CommandBuffer::null() {
            return Err(input("cmd: VK_NULL_HANDLE"));
        }
        // SAFETY: `cmd` is recording outside a render pass on a compute queue of the device
        // the warper was built on, once (the caller's contract, stated above).
        unsafe { w.warper.record_prepare(cmd) };
        Ok(())
    })
}

/// Records the warp of `source` into `output` and, when given, `mask`.
///
/// Images: 2D, one mip level and layer, each with a view of that level and layer. `source`
/// is vkl_warper_source_size, `output` and `mask` are vkl_warper_output_size. `source` and
/// `output` are of the options' format; `mask` is VK_FORMAT_R8_UNORM, written 255 where the
/// pixel has a source and 0 where it has none (NULL: the warper writes its own).
///
/// Usage: VK_IMAGE_USAGE_STORAGE_BIT on all three.
///
/// Layouts: all three are in VK_IMAGE_LAYOUT_GENERAL on entry and are left in it.
///
/// Synchronization: one compute dispatch, in VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, reading
/// `source` (VK_ACCESS_SHADER_READ_BIT, storage-image loads) and writing `output` and
/// `mask` (VK_ACCESS_SHADER_WRITE_BIT). The caller's barriers make its writes of `source`
/// visible to that stage and access before, and the warp's writes visible to whatever reads
/// `output` and `mask` after. It changes the bound compute pipeline and descriptor sets.
///
/// Never submits, never waits, not inside a render pass. The sizes and views are checked
/// first: a call that returns an error records nothing.
///
/// Frames in flight: the warper keeps one descriptor set per frame in flight (N, the options'
/// frames_in_flight) and the k-th call uses set k mod N, rewriting it only when the views
/// differ from those it last held. Up to N - 1 earlier warps may still execute while this one
/// is recorded; the warp recorded N calls before must have completed when the views change.
///
/// # Safety
/// `w` is NULL or a live warper on which vkl_warper_record_prepare was recorded first (in
/// this or an earlier submission); `source`, `output` and `mask` are NULL or readable
/// `vkl_image`s whose images stay alive until the work completes; `cmd` is recording outside
/// a render pass on a compute queue of the warper's device.
#[no_mangle]
pub unsafe extern "C" fn vkl_warper_record(
    w: vkl_warper,
    cmd: VkCommandBuffer,
    source: *const vkl_image,
    output: *const vkl_image,
    mask: *const vkl_image,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live warper, used by one thread at a time (the caller's contract).
        let w = unsafe { w.as_mut() }.ok_or_else(|| input("warper: NULL pointer"))?;
        if cmd == vk::CommandBuffer::null() {
            return Err(input("cmd: VK_NULL_HANDLE"));
        }
        let image = |i: &vkl_image| ImageRef {
            image: i.image,
            view: i.view,
            width: i.width,
            height: i.height,
        };
        // SAFETY: NULL or readable images (the caller's contract).
        let (source, output, mask) = unsafe {
            (
                image(arg(source, "source")?),
                image(arg(output, "output")?),
                mask.as_ref().map(image),
            )
        };
        // SAFETY: the caller's contract above is `Warper::record`'s: recording outside a
        // render pass after record_prepare, images alive and in GENERAL, no pending warp of
        // this warper when the views change.
        unsafe { w.warper.record(cmd, &source, &output, mask.as_ref()) }
    })
}

/// Frees a warper and sets `*w` to NULL. The caller ensures the GPU no longer uses it (the
/// submissions that recorded it have completed).
///
/// # Safety
/// `w` is NULL or points to NULL or to a warper this library returned.
#[no_mangle]
pub unsafe extern "C" fn vkl_warper_free(w: *mut vkl_warper) {
    // SAFETY: the caller's contract, as `free` needs it.
    release(|| unsafe { free(w) })
}

// ---------------------------------------------------------------------------------------------
// Scenes

/// vklens's own headless Vulkan device: the device scene rendering runs on. A scene render
/// submits work and waits for it, which vklens never does on the caller's queue (vkl_gpu), so
/// scenes get a device of their own, as the command line and the Python package do.
pub struct vkl_device_s {
    device: Device,
    name: CString,
}

/// A device handle, made by vkl_device_create. vkl_scene_render may be called from several
/// threads on one device (its submissions are serialized).
pub type vkl_device = *mut vkl_device_s;

/// Opens vklens's own headless device: its own instance, device and queue, none of the
/// caller's. The environment picks it as for the command line: `VKLENS_DEVICE` (`cpu` for
/// lavapipe, `gpu`, an index or a part of the device name; default: the fastest), and
/// `VKLENS_VALIDATION=1` turns the Khronos validation layer on (see
/// vkl_device_check_validation). No Vulkan library or device is VKL_ERROR_UNSUPPORTED or
/// VKL_ERROR_VULKAN.
///
/// # Safety
/// `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_device_create(out: *mut vkl_device) -> vkl_error {
    guard(|| {
        if out.is_null() {
            return Err(input("out: NULL pointer"));
        }
        let device = Device::new()?;
        let name = CString::new(device.name().replace('\0', " ")).unwrap_or_default();
        let handle = Box::into_raw(Box::new(vkl_device_s { device, name }));
        // SAFETY: non-null (checked) and writable (the caller's contract).
        unsafe { out.write(handle) };
        Ok(())
    })
}

/// The device's name as the driver reports it (UTF-8, NUL-terminated), valid until
/// vkl_device_free; NULL for a NULL device.
///
/// # Safety
/// `d` is NULL or a live device.
#[no_mangle]
pub unsafe extern "C" fn vkl_device_name(d: vkl_device) -> *const c_char {
    // SAFETY: NULL or a live device (the caller's contract).
    match unsafe { d.as_ref() } {
        Some(d) => d.name.as_ptr(),
        None => ptr::null(),
    }
}

/// VKL_ERROR_VULKAN listing the validation layer's messages if it was on (VKLENS_VALIDATION=1)
/// and has reported anything on this device so far; NULL otherwise.
///
/// # Safety
/// `d` is NULL or a live device.
#[no_mangle]
pub unsafe extern "C" fn vkl_device_check_validation(d: vkl_device) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live device (the caller's contract).
        let d = unsafe { arg(d, "device")? };
        d.device.check_validation()
    })
}

/// Closes the device and sets `*d` to NULL. Frames already rendered on it stay valid (they
/// are host memory); no render on it may be running.
///
/// # Safety
/// `d` is NULL or points to NULL or to a device this library returned.
#[no_mangle]
pub unsafe extern "C" fn vkl_device_free(d: *mut vkl_device) {
    // SAFETY: the caller's contract, as `free` needs it.
    release(|| unsafe { free(d) })
}

/// A scene file planned for rendering: its geometry loaded, its camera read, the pipeline
/// chosen (vkl_scene_explain says which and why).
pub struct vkl_scene_s {
    scene: SceneRenderer,
}

/// A scene handle. Immutable: safe to use from any thread, also to render on several threads
/// at once.
pub type vkl_scene = *mut vkl_scene_s;

/// `p` as a string, or an input error naming `what`.
///
/// # Safety
/// `p` is NULL or NUL-terminated.
unsafe fn arg_str<'a>(p: *const c_char, what: &str) -> Result<&'a str, Error> {
    // SAFETY: NULL or NUL-terminated (the caller's contract).
    unsafe { option_str(p, what)? }.ok_or_else(|| input(format!("{what}: NULL pointer")))
}

fn new_scene(out: *mut vkl_scene, scene: SceneRenderer) -> Result<(), Error> {
    let handle = Box::into_raw(Box::new(vkl_scene_s { scene }));
    // SAFETY: `out` was checked non-null by the caller of `new_scene`, and is writable (the C
    // caller's contract).
    unsafe { out.write(handle) };
    Ok(())
}

/// Reads a scene file (TOML, as `vklens render --scene` reads it; see
/// examples/scenes/README.md) and plans it: relative paths in it (the camera, a mesh) are
/// resolved against the file's folder. A missing or unreadable file is VKL_ERROR_IO naming
/// the path; a malformed one (TOML, an unknown key or value) is VKL_ERROR_INPUT naming the
/// file and the key. No Vulkan needed.
///
/// # Safety
/// `path` is NULL or a NUL-terminated string; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_scene_load(path: *const c_char, out: *mut vkl_scene) -> vkl_error {
    guard(|| {
        if out.is_null() {
            return Err(input("out: NULL pointer"));
        }
        // SAFETY: NULL or NUL-terminated (the caller's contract).
        let path = std::path::Path::new(unsafe { arg_str(path, "path")? });
        // The planner reports an unreadable file as bad input; opening it first makes it an
        // I/O error, as for vkl_camera_load, so that the caller can tell a wrong path from a
        // wrong file.
        std::fs::File::open(path).map_err(|e| Error::io(path, "cannot read scene file", &e))?;
        new_scene(out, SceneRenderer::load(path)?)
    })
}

/// Parses a scene file's text (TOML) and plans it. `base_path` is the path of the file the
/// text stands for: relative paths in the text are resolved against its folder, and
/// messages name it. NULL = "scene.toml" in the working folder. Errors as vkl_scene_load's
/// for a malformed text. No Vulkan needed.
///
/// # Safety
/// `toml_text` and `base_path` are NULL or NUL-terminated strings; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_scene_parse(
    toml_text: *const c_char,
    base_path: *const c_char,
    out: *mut vkl_scene,
) -> vkl_error {
    guard(|| {
        if out.is_null() {
            return Err(input("out: NULL pointer"));
        }
        // SAFETY (both): NULL or NUL-terminated (the caller's contract).
        let text = unsafe { arg_str(toml_text, "toml_text")? };
        let base = unsafe { option_str(base_path, "base_path")? }.unwrap_or("scene.toml");
        new_scene(out, SceneRenderer::parse(text, base)?)
    })
}

/// How many frames (poses) the scene has: vkl_scene_render takes 0 to count - 1.
///
/// # Safety
/// `s` is NULL or a live scene; `count` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_scene_frame_count(s: vkl_scene, count: *mut usize) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live scene; NULL (refused) or writable (the caller's contract).
        unsafe { put(count, "count", arg(s, "scene")?.scene.frame_count()) }
    })
}

/// The largest geometric error the plan's approximations leave, in output pixels, as
/// measured while planning (the scene's `[accuracy] max_error_px` bounds it).
///
/// # Safety
/// `s` is NULL or a live scene; `px` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_scene_expected_error_px(s: vkl_scene, px: *mut f64) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live scene; NULL (refused) or writable (the caller's contract).
        unsafe { put(px, "px", arg(s, "scene")?.scene.expected_error_px()) }
    })
}

/// The plan as `vklens render --explain` prints it (the route, each step with the reason it
/// is there, the expected error against the budget): a new UTF-8, NUL-terminated string
/// written to `*out`, which the caller frees with vkl_string_free.
///
/// # Safety
/// `s` is NULL or a live scene; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_scene_explain(s: vkl_scene, out: *mut *mut c_char) -> vkl_error {
    guard(|| {
        if out.is_null() {
            return Err(input("out: NULL pointer"));
        }
        // SAFETY: NULL or a live scene (the caller's contract).
        let s = unsafe { arg(s, "scene")? };
        let text = CString::new(s.scene.explain().replace('\0', " ")).unwrap_or_default();
        // SAFETY: non-null (checked) and writable (the caller's contract).
        unsafe { out.write(text.into_raw()) };
        Ok(())
    })
}

/// Frees a string this library returned (vkl_scene_explain's) and sets `*s` to NULL.
/// `s == NULL` and `*s == NULL` are harmless. Never pass it memory of another allocator.
///
/// # Safety
/// `s` is NULL or points to NULL or to a string this library returned and did not free.
#[no_mangle]
pub unsafe extern "C" fn vkl_string_free(s: *mut *mut c_char) {
    release(|| {
        if s.is_null() {
            return;
        }
        // SAFETY: the caller's contract: `*s` is NULL or came from `CString::into_raw`; it is
        // nulled so that a second free through the same variable sees NULL.
        unsafe {
            let inner = s.replace(ptr::null_mut());
            if !inner.is_null() {
                drop(CString::from_raw(inner));
            }
        }
    })
}

/// Frees a scene and sets `*s` to NULL. Frames rendered from it stay valid.
///
/// # Safety
/// `s` is NULL or points to NULL or to a scene this library returned.
#[no_mangle]
pub unsafe extern "C" fn vkl_scene_free(s: *mut vkl_scene) {
    // SAFETY: the caller's contract, as `free` needs it.
    release(|| unsafe { free(s) })
}

// The header's thread rules for devices, scenes and frames rest on these being Send + Sync
// (a device serializes its submissions): this fails to build if one stops being so.
const _: fn() = || {
    fn shared<T: Send + Sync>() {}
    shared::<vkl_device_s>();
    shared::<vkl_scene_s>();
    shared::<vkl_frame_s>();
};

/// One rendered frame: the outputs its scene asks for, in host memory.
pub struct vkl_frame_s {
    frame: Frame,
    /// The scene's objects with their names and classes.
    objects: Vec<vklens_core::labels::ObjectLabel>,
}

/// A frame handle, made by vkl_scene_render. Immutable: safe to read from any thread.
pub type vkl_frame = *mut vkl_frame_s;

/// Renders frame `frame_index` (the scene's pose of that index, 0-based) on `d` and waits for
/// it: the outputs come back in host memory, in a new frame written to `*out`. An index past
/// the scene's poses is VKL_ERROR_INPUT naming frame_index; work the device cannot do is
/// VKL_ERROR_UNSUPPORTED.
///
/// # Safety
/// `d` and `s` are NULL or live handles; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_scene_render(
    d: vkl_device,
    s: vkl_scene,
    frame_index: usize,
    out: *mut vkl_frame,
) -> vkl_error {
    guard(|| {
        if out.is_null() {
            return Err(input("out: NULL pointer"));
        }
        // SAFETY: NULL or live handles (the caller's contract).
        let (d, s) = unsafe { (arg(d, "device")?, arg(s, "scene")?) };
        let count = s.scene.frame_count();
        if frame_index >= count {
            return Err(input(format!(
                "frame_index: {frame_index}, but the scene has {count} pose(s) (0 to {})",
                count.saturating_sub(1)
            )));
        }
        let mut rendered = None;
        s.scene
            .render(&d.device, frame_index..frame_index + 1, &mut |f| {
                rendered = Some(f);
                Ok(())
            })?;
        let frame = rendered.ok_or_else(|| {
            Error::internal(format!("frame {frame_index}: the renderer returned none"))
        })?;
        let objects = s.scene.objects().to_vec();
        let handle = Box::into_raw(Box::new(vkl_frame_s { frame, objects }));
        // SAFETY: non-null (checked) and writable (the caller's contract).
        unsafe { out.write(handle) };
        Ok(())
    })
}

/// `(width, height)` of every output of the frame.
///
/// # Safety
/// `f` is NULL or a live frame; `width` and `height` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_frame_size(
    f: vkl_frame,
    width: *mut u32,
    height: *mut u32,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live frame (the caller's contract).
        let r = &unsafe { arg(f, "frame")? }.frame.rendered;
        // SAFETY: NULL (refused) or writable (the caller's contract).
        unsafe { put_size(width, height, (r.width, r.height)) }
    })
}

/// The frame's pose index in its scene, and the wall time of its GPU work in milliseconds.
/// Either pointer may be NULL when that value is not wanted.
///
/// # Safety
/// `f` is NULL or a live frame; `index` and `ms` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_frame_info(
    f: vkl_frame,
    index: *mut usize,
    ms: *mut f64,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live frame (the caller's contract).
        let f = &unsafe { arg(f, "frame")? }.frame;
        // SAFETY (both): non-null and writable (the caller's contract).
        if !index.is_null() {
            unsafe { index.write(f.index) };
        }
        if !ms.is_null() {
            unsafe { ms.write(f.ms) };
        }
        Ok(())
    })
}

/// An output of a rendered frame (the scene file's `[outputs]` table asks for them).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum vkl_output {
    /// The colour image (`[outputs] color`).
    VKL_OUTPUT_COLOR = 0,
    /// Object IDs, 0 = background (`[outputs] ids`).
    VKL_OUTPUT_IDS,
    /// Camera-frame z in metres, +infinity where nothing was drawn (`[outputs] depth`).
    VKL_OUTPUT_DEPTH,
    /// Pixel motion (dx, dy) since the previous pose, NaN where unknown or background
    /// (`[outputs] flow`).
    VKL_OUTPUT_FLOW,
    /// Distance in metres from the projection centre along each pixel's ray, +infinity where
    /// nothing was drawn (`[outputs] range`).
    VKL_OUTPUT_RANGE,
    /// Each pixel's class by the scene's `[classes]` patterns, 0 for the background and for
    /// objects no pattern matches (`[outputs] classes`).
    VKL_OUTPUT_CLASSES,
}

/// How an output's pixels are stored: row-major from the top row, rows tightly packed
/// (width × the pixel's bytes), the host's byte order.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum vkl_pixel_format {
    /// The frame does not have this output (the scene did not ask for it).
    VKL_PIXELS_NONE = 0,
    /// 4 bytes per pixel: R, G, B, A, 0 to 255 (colour; as VK_FORMAT_R8G8B8A8_UNORM).
    VKL_PIXELS_RGBA8,
    /// 4 floats per pixel: R, G, B, A, linear 0 to 1 and above for HDR (colour when the scene
    /// asks for float output; as VK_FORMAT_R32G32B32A32_SFLOAT).
    VKL_PIXELS_RGBA32F,
    /// 1 uint32_t per pixel (IDs).
    VKL_PIXELS_R32_UINT,
    /// 1 float per pixel (depth).
    VKL_PIXELS_R32F,
    /// 2 floats per pixel, x then y (flow).
    VKL_PIXELS_RG32F,
}

/// The bytes of `which` in `frame`, and their format; `None` when the frame lacks it.
fn output_bytes(frame: &Frame, which: u32) -> Result<Option<(vkl_pixel_format, &[u8])>, Error> {
    use vkl_pixel_format::*;
    /// The bytes of a slice of plain numbers (u8, u32 or f32, alone or in arrays: no padding,
    /// every bit pattern valid as u8).
    fn bytes<T: Copy>(v: &[T]) -> &[u8] {
        // SAFETY: `v` is a live slice of `size_of_val(v)` initialized bytes (T is only ever a
        // padding-free number type or array of one, see the callers), u8 has alignment 1, and
        // the result borrows `v`.
        unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u8>(), std::mem::size_of_val(v)) }
    }
    let r = &frame.rendered;
    Ok(match which {
        0 => r.color.as_ref().map(|c| match &c.pixels {
            Pixels::Rgba8(p) => (VKL_PIXELS_RGBA8, bytes(p)),
            Pixels::Rgba32F(p) => (VKL_PIXELS_RGBA32F, bytes(p)),
            Pixels::R32Uint(p) => (VKL_PIXELS_R32_UINT, bytes(p)),
        }),
        1 => r.ids.as_deref().map(|p| (VKL_PIXELS_R32_UINT, bytes(p))),
        2 => r.depth.as_deref().map(|p| (VKL_PIXELS_R32F, bytes(p))),
        3 => r.flow.as_deref().map(|p| (VKL_PIXELS_RG32F, bytes(p))),
        4 => r.range.as_deref().map(|p| (VKL_PIXELS_R32F, bytes(p))),
        5 => frame
            .labels
            .classes
            .as_deref()
            .map(|p| (VKL_PIXELS_R32_UINT, bytes(p))),
        w => {
            return Err(input(format!(
                "which: {w} (expected VKL_OUTPUT_COLOR, VKL_OUTPUT_IDS, VKL_OUTPUT_DEPTH, VKL_OUTPUT_FLOW, VKL_OUTPUT_RANGE or VKL_OUTPUT_CLASSES)"
            )))
        }
    })
}

/// Whether the frame has output `which` (a vkl_output), its format and its size in bytes:
/// VKL_PIXELS_NONE and 0 when the scene did not ask for it (not an error). Either pointer may
/// be NULL when that value is not wanted.
///
/// # Safety
/// `f` is NULL or a live frame; `format` and `bytes` are NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_frame_output(
    f: vkl_frame,
    which: u32,
    format: *mut vkl_pixel_format,
    bytes: *mut usize,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live frame (the caller's contract).
        let f = &unsafe { arg(f, "frame")? }.frame;
        let (fmt, len) = match output_bytes(f, which)? {
            Some((fmt, b)) => (fmt, b.len()),
            None => (vkl_pixel_format::VKL_PIXELS_NONE, 0),
        };
        // SAFETY (both): non-null and writable (the caller's contract).
        if !format.is_null() {
            unsafe { format.write(fmt) };
        }
        if !bytes.is_null() {
            unsafe { bytes.write(len) };
        }
        Ok(())
    })
}

/// Copies output `which` (a vkl_output) into the caller's `dst` of `dst_bytes` bytes, laid out
/// as vkl_pixel_format says; vkl_frame_output gives the size. `dst` stays the caller's, the
/// frame keeps its own copy. A `dst_bytes` smaller than the output, or an output the scene did
/// not ask for, is VKL_ERROR_INPUT and copies nothing; bytes past the output's are untouched.
///
/// # Safety
/// `f` is NULL or a live frame; `dst` is NULL or points to `dst_bytes` writable bytes that do
/// not overlap the frame.
#[no_mangle]
pub unsafe extern "C" fn vkl_frame_copy(
    f: vkl_frame,
    which: u32,
    dst: *mut std::ffi::c_void,
    dst_bytes: usize,
) -> vkl_error {
    guard(|| {
        // SAFETY: NULL or a live frame (the caller's contract).
        let f = &unsafe { arg(f, "frame")? }.frame;
        let name = ["color", "ids", "depth", "flow", "range", "classes"]
            .get(which as usize)
            .copied();
        let Some((_, src)) = output_bytes(f, which)? else {
            let name = name.unwrap_or("?");
            return Err(input(format!(
                "which: the frame has no {name} (the scene's [outputs] {name} is not true)"
            )));
        };
        if dst.is_null() {
            return Err(input("dst: NULL pointer"));
        }
        if dst_bytes < src.len() {
            return Err(input(format!(
                "dst_bytes: {dst_bytes}, but the output is {} bytes",
                src.len()
            )));
        }
        // SAFETY: `dst` is non-null (checked), has `dst_bytes` ≥ `src.len()` writable bytes
        // and does not overlap the frame (the caller's contract).
        unsafe { ptr::copy_nonoverlapping(src.as_ptr(), dst.cast::<u8>(), src.len()) };
        Ok(())
    })
}

/// The frame's labels as JSON: a new UTF-8, NUL-terminated string written to `*out`, which the
/// caller frees with vkl_string_free. One object: `"objects"` (every object's `id`, `name`
/// and `class`), and where the scene asks for them `"boxes"` and `"keypoints"`, in the shapes
/// of `vklens render`'s boxes_NNNN.json and keypoints_NNNN.json (examples/scenes/README.md).
///
/// # Safety
/// `f` is NULL or a live frame; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn vkl_frame_labels_json(f: vkl_frame, out: *mut *mut c_char) -> vkl_error {
    guard(|| {
        if out.is_null() {
            return Err(input("out: NULL pointer"));
        }
        // SAFETY: NULL or a live frame (the caller's contract).
        let f = unsafe { arg(f, "frame")? };
        let mut json = serde_json::json!({ "objects": f.objects });
        if let Some(b) = &f.frame.labels.boxes {
            json["boxes"] = serde_json::to_value(b).map_err(|e| Error::internal(e.to_string()))?;
        }
        if let Some(k) = &f.frame.labels.keypoints {
            json["keypoints"] =
                serde_json::to_value(k).map_err(|e| Error::internal(e.to_string()))?;
        }
        let text = CString::new(json.to_string().replace('\0', " ")).unwrap_or_default();
        // SAFETY: non-null (checked) and writable (the caller's contract).
        unsafe { out.write(text.into_raw()) };
        Ok(())
    })
}

/// Frees a frame and sets `*f` to NULL.
///
/// # Safety
/// `f` is NULL or points to NULL or to a frame this library returned.
#[no_mangle]
pub unsafe extern "C" fn vkl_frame_free(f: *mut vkl_frame) {
    // SAFETY: the caller's contract, as `free` needs it.
    release(|| unsafe { free(f) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use vklens_core::model::{samples::sample_cameras, BrownRadial, ModelKind};

    /// The C name of every model of the library's list, through a camera of that model.
    #[test]
    fn vkl_camera_model_names_every_model_as_camera_files_do() {
        let mut named = Vec::new();
        let brown = Camera::from_brown(&BrownRadial::new(800, 600, 0.15, 0.1).unwrap()).unwrap();
        let cameras = sample_cameras().unwrap();
        for (label, camera) in cameras.into_iter().chain([("brown", brown)]) {
            let expected = if label == "brown" {
                "brown"
            } else {
                camera.model().name()
            };
            let mut handle: vkl_camera = ptr::null_mut();
            new_camera(&mut handle, camera).unwrap();
            // SAFETY: `handle` is the live camera just made; the name is static.
            let name = unsafe { CStr::from_ptr(vkl_camera_model(handle)) };
            assert_eq!(name.to_str().unwrap(), expected, "{label}");
            // SAFETY: made above, freed once.
            unsafe { vkl_camera_free(&mut handle) };
            named.push(expected);
        }
        for kind in ModelKind::ALL {
            assert!(
                named.contains(&kind.name()),
                "no sample camera of {}",
                kind.name()
            );
            // SAFETY: the name is static.
            let listed = unsafe { CStr::from_ptr(vkl_model_name(kind.gpu_id() as usize)) };
            assert_eq!(listed.to_str().unwrap(), kind.name());
        }
        assert!(vkl_model_name(ModelKind::ALL.len()).is_null());
        // SAFETY: NULL is allowed.
        assert!(unsafe { vkl_camera_model(ptr::null_mut()) }.is_null());
    }
}
