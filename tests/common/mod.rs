//! Shared test helpers.
#![allow(dead_code)]

use vklens::internal::host::{Context, ContextOptions};

/// A headless context with the Khronos validation layer on (tests always validate).
pub fn validated_context() -> Context {
    Context::new(ContextOptions {
        validation: true,
        device: std::env::var("VKLENS_DEVICE")
            .ok()
            .filter(|s| !s.is_empty()),
        geometry_shader: vklens::internal::host::geometry_shader_from_env(),
        geometry_shader_discard: vklens::internal::host::geometry_shader_discard_from_env(),
    })
    .expect("a Vulkan device with the validation layer (README: the test command installs both)")
}

/// Fails the test if the validation layer said anything.
pub fn assert_no_validation_messages(ctx: &Context) {
    if let Err(e) = ctx.check_validation() {
        panic!("{e}");
    }
}

/// The shared reference case named `name`, as a camera.
pub fn reference_camera(name: &str) -> vklens::internal::model::Camera {
    let reference =
        vklens::internal::io::reference::load_reference().expect("shared reference file");
    reference
        .cases
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no reference case {name}"))
        .camera()
        .expect("reference cases are valid cameras")
}

/// A lens file shipped in `lenses/`.
pub fn shipped_lens(name: &str) -> vklens::internal::lens::Prescription {
    vklens::internal::lens::Prescription::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("lenses")
            .join(name),
    )
    .expect("shipped lens files parse")
}

/// Uploads a mesh (and its texture) for drawing.
pub fn upload_mesh(
    ctx: &Context,
    mesh: &vklens::internal::scene::Mesh,
    texture: Option<&vklens::internal::imaging::Raster>,
) -> vklens::internal::pass::geometry::MeshBuffers {
    let buffers =
        vklens::internal::pass::geometry::MeshBuffers::new(ctx.gpu(), mesh, texture).unwrap();
    ctx.submit(|cmd| {
        unsafe { buffers.record_upload(cmd) };
        Ok(())
    })
    .unwrap();
    buffers
}
