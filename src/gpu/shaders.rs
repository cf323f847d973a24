//! SPIR-V compiled from `glsl/` by `build.rs`.

/// `glsl/points.comp`: the camera model on a list of points (forward or inverse).
pub const POINTS_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/points.comp.spv"));
/// `glsl/points.comp` compiled with `VKL_F64`: the same model in f64 (needs `shaderFloat64`).
pub const POINTS_COMP_F64: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/points.comp.f64.spv"));
/// `glsl/points.comp`'s modes 0 and 2 alone (distort, project), f32 and f64.
pub const POINTS_COMP_FORWARD: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/points.comp.forward.spv"));
pub const POINTS_COMP_FORWARD_F64: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/points.comp.forward_f64.spv"));
/// `glsl/points.comp`'s modes 1 and 3 alone (undistort, unproject), f32 and f64.
pub const POINTS_COMP_INVERSE: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/points.comp.inverse.spv"));
pub const POINTS_COMP_INVERSE_F64: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/points.comp.inverse_f64.spv"));
/// `glsl/grid_demo.comp`: a procedural grid seen through a lens (analytic inverse per pixel).
pub const GRID_DEMO_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/grid_demo.comp.spv"));
/// `glsl/warp.comp`, rgba32f images (16-bit and float data).
pub const WARP_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/warp.comp.spv"));
/// `glsl/warp.comp`, rgba8 images (8-bit data).
pub const WARP_COMP_RGBA8: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/warp.comp.rgba8.spv"));
/// `glsl/warp.comp`, rgba32f images, MODE 1 (undistort) alone: the forward model, no inverse.
pub const WARP_COMP_FORWARD: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/warp.comp.forward.spv"));
/// `glsl/warp.comp`, rgba8 images, MODE 1 (undistort) alone: the forward model, no inverse.
pub const WARP_COMP_RGBA8_FORWARD: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/warp.comp.rgba8_forward.spv"));
/// `glsl/warp.comp`, r32ui images (object IDs, nearest only).
pub const WARP_COMP_R32UI: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/warp.comp.r32ui.spv"));
/// `glsl/warp.comp`, r32f images (depth, nearest only).
pub const WARP_COMP_R32F: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/warp.comp.r32f.spv"));
/// `glsl/sphere_warp.comp`: the warp from a cube map of six pinhole faces.
pub const SPHERE_WARP_COMP: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/sphere_warp.comp.spv"));
/// `glsl/sphere_warp.comp` from a cube map into an rgba8 target (8-bit colour).
pub const SPHERE_WARP_COMP_RGBA8: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/sphere_warp.comp.rgba8.spv"));
/// `glsl/sphere_warp.comp` sampling an equirectangular panorama.
pub const SPHERE_WARP_COMP_EQUIRECT: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/sphere_warp.comp.equirect.spv"));
/// `glsl/inverse_map.comp`: a coordinate map per camera and channel.
pub const INVERSE_MAP_COMP: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/inverse_map.comp.spv"));
/// `glsl/copy.comp`: the copy pass the warp is measured against.
pub const COPY_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/copy.comp.spv"));
/// `glsl/upsample_map.comp`: a full-resolution map from a coarse one (+ Newton refinement).
pub const UPSAMPLE_MAP_COMP: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/upsample_map.comp.spv"));
/// `glsl/geometry.vert`: Lambers et al. Alg. 1 (or a pinhole projection) per vertex.
pub const GEOMETRY_VERT: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/geometry.vert.spv"));
/// `glsl/geometry.vert` for the geometry-shader path of a frame seen from one pose (no readout
/// solve).
pub const GEOMETRY_VERT_GLOBAL: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/geometry.vert.global.spv"));
/// `glsl/geometry.vert` without the discard data: the pinhole render (no geometry shader).
pub const GEOMETRY_VERT_PINHOLE: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/geometry.vert.pinhole.spv"));
/// `glsl/geometry.vert`'s pinhole render of a still frame: no lens model, no readout solve.
pub const GEOMETRY_VERT_PLAIN: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/geometry.vert.plain.spv"));
/// `glsl/geometry.vert` reading the positions the compute discard computed.
pub const GEOMETRY_VERT_PULLED: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/geometry.vert.pulled.spv"));
/// `glsl/geometry.vert` reading the positions and flow the compute discard computed.
pub const GEOMETRY_VERT_PULLED_FLOW: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/geometry.vert.pulled_flow.spv"));
/// `glsl/geometry.geom`: Lambers et al. Sec. 3.2's triangle discard.
pub const GEOMETRY_GEOM: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/geometry.geom.spv"));
/// `glsl/discard.comp`: Lambers et al. Sec. 3.2's triangle discard without a geometry shader.
pub const DISCARD_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/discard.comp.spv"));
/// `glsl/discard.comp`'s stage 0 for a frame every line sees from one pose (no readout solve).
pub const DISCARD_COMP_GLOBAL: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/discard.comp.global.spv"));
/// `glsl/discard.comp`'s stage 0 for a moving rolling shutter: the bounded readout solve alone,
/// what it does not cover left to stage 3 (`DISCARD_COMP`).
pub const DISCARD_COMP_BOUNDED: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/discard.comp.bounded.spv"));
/// `glsl/discard.comp`'s stages 1 and 2 alone (no Alg. 1 to compile).
pub const DISCARD_COMP_INDICES: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/discard.comp.indices.spv"));
/// `glsl/geometry.frag`: colour, object ID, flow and depth outputs.
pub const GEOMETRY_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/geometry.frag.spv"));
/// `glsl/mesh_warp.vert`: the Durham radial-correction paper's mesh-based warp (grid vertices with source coordinates).
pub const MESH_WARP_VERT: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/mesh_warp.vert.spv"));
/// `glsl/mesh_warp.frag`: samples the source (or writes the interpolated coordinate).
pub const MESH_WARP_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/mesh_warp.frag.spv"));
/// `glsl/film_morph.vert`: Heidrich et al.'s morph of a cell's perspective image onto its film grid.
pub const FILM_MORPH_VERT: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/film_morph.vert.spv"));
/// `glsl/film_morph.frag`: the weighted, additive accumulation into the float film.
pub const FILM_MORPH_FRAG: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/film_morph.frag.spv"));
/// `glsl/warp_raster.vert`: one triangle over the whole framebuffer.
pub const WARP_RASTER_VERT: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/warp_raster.vert.spv"));
/// `glsl/warp_raster.frag`: the map warp per fragment, rgba32f source.
pub const WARP_RASTER_FRAG: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/warp_raster.frag.spv"));
/// `glsl/warp_raster.frag`, rgba8 source.
pub const WARP_RASTER_FRAG_RGBA8: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/warp_raster.frag.rgba8.spv"));

// `<SHADER>_BY_MODEL`: the shaders marked `// vklens:per-model`, once per model of the list.
include!(concat!(env!("OUT_DIR"), "/per_model.rs"));
