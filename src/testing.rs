//! Helpers shared by the unit tests of every layer: a validated device, the shared reference
//! cameras, the shipped lenses, a mesh on the GPU.

use crate::host::{geometry_shader_discard_from_env, geometry_shader_from_env};
use crate::host::{Context, ContextOptions};
use std::sync::OnceLock;

/// The test binary's headless context with the Khronos validation layer on (tests always
/// validate), shared by its tests: one device per binary, not one per test, so that a
/// pipeline one test built is there for the next (`gpu::PipelineMemo`). The validation
/// messages are the device's, so a message any test causes fails every test that checks
/// after it. A test that needs a device of its own (to own it, or to open it with other
/// options) calls [`new_validated_context`] or `Context::new`.
pub(crate) fn validated_context() -> &'static Context {
    static SHARED: OnceLock<Context> = OnceLock::new();
    SHARED.get_or_init(new_validated_context)
}

/// A headless context of its own with the validation layer on.
pub(crate) fn new_validated_context() -> Context {
    Context::new(ContextOptions {
        validation: true,
        device: std::env::var("VKLENS_DEVICE")
            .ok()
            .filter(|s| !s.is_empty()),
        geometry_shader: geometry_shader_from_env(),
        geometry_shader_discard: geometry_shader_discard_from_env(),
        pipeline_cache: None,
    })
    .expect("a Vulkan device with the validation layer (README: the test command installs both)")
}

/// Fails the test if the validation layer said anything.
pub(crate) fn assert_no_validation_messages(ctx: &Context) {
    if let Err(e) = ctx.check_validation() {
        panic!("{e}");
    }
}

/// The shared reference case named `name`, as a camera.
pub(crate) fn reference_camera(name: &str) -> crate::model::Camera {
    let reference = crate::io::reference::load_reference().expect("shared reference file");
    reference
        .cases
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no reference case {name}"))
        .camera()
        .expect("reference cases are valid cameras")
}

/// A lens file shipped in `lenses/`.
pub(crate) fn shipped_lens(name: &str) -> crate::lens::Prescription {
    crate::lens::Prescription::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("lenses")
            .join(name),
    )
    .expect("shipped lens files parse")
}

/// Uploads a mesh (and its texture) for drawing.
pub(crate) fn upload_mesh(
    ctx: &Context,
    mesh: &crate::scene::Mesh,
    texture: Option<&crate::imaging::Raster>,
) -> crate::pass::geometry::MeshBuffers {
    let buffers = crate::pass::geometry::MeshBuffers::new(ctx.gpu(), mesh, texture).unwrap();
    ctx.submit(|cmd| {
        // SAFETY: `submit` hands a command buffer recording outside a render pass and waits for
        // it; the buffers outlive the submission.
        unsafe { buffers.record_upload(cmd) };
        Ok(())
    })
    .unwrap();
    buffers
}
