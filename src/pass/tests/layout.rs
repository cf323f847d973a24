//! One struct, one layout: the host structs against the compiled SPIR-V's block offsets, and
//! the specialization constants the shaders declare against the ids the host sets.

use std::mem::offset_of;

use crate::gpu::SpecId;
use crate::gpu::{reflect, shaders};
use crate::pass::{spec, CameraParams, CameraParams64};

macro_rules! host_offsets {
    ($t:ty) => {
        vec![
            ("intrinsics", offset_of!($t, intrinsics)),
            ("radial", offset_of!($t, radial)),
            ("rational", offset_of!($t, rational)),
            ("tangential_prism", offset_of!($t, tangential_prism)),
            ("prism", offset_of!($t, prism)),
            ("tilt", offset_of!($t, tilt)),
            ("untilt", offset_of!($t, untilt)),
            ("domain_info", offset_of!($t, domain_info)),
        ]
    };
}

/// The camera block: the scalar members as one struct (`VklCamera`, [`host_offsets`]), which
/// the shaders copy out at the top of main(), then the arrays.
macro_rules! block_offsets {
    ($t:ty) => {
        vec![
            ("values", 0),
            ("model", offset_of!($t, model)),
            ("domain", offset_of!($t, domain)),
        ]
    };
}

/// Checks the camera block `block` of `spirv` and its struct of scalar members against `$t`.
macro_rules! check_camera {
    ($spirv:expr, $block:expr, $t:ty) => {
        check($spirv, "VklCamera", host_offsets!($t));
        check($spirv, $block, block_offsets!($t));
    };
}

fn check(spirv: &[u8], block: &str, host: Vec<(&str, usize)>) {
    let device =
        reflect::member_offsets(spirv, block).unwrap_or_else(|| panic!("no block {block}"));
    let device: Vec<(String, usize)> = device.into_iter().map(|(n, o)| (n, o as usize)).collect();
    let host: Vec<(String, usize)> = host.into_iter().map(|(n, o)| (n.to_string(), o)).collect();
    assert_eq!(
        device, host,
        "{block}: GLSL (left) and Rust (right) layouts differ"
    );
}

#[test]
fn camera_params_f32_matches_the_glsl_block() {
    check_camera!(shaders::POINTS_COMP, "CameraParams", CameraParams);
    check_camera!(shaders::GRID_DEMO_COMP, "CameraParams", CameraParams);
    check_camera!(shaders::WARP_COMP, "CameraParams", CameraParams);
    check_camera!(shaders::DISCARD_COMP, "CameraParams", CameraParams);
}

#[test]
fn camera_params_f64_matches_the_glsl_block() {
    check_camera!(shaders::POINTS_COMP_F64, "CameraParams64", CameraParams64);
}

#[test]
fn shaders_declare_the_spec_constants_the_host_sets() {
    // Every id the host sets, under its name, in every shader it is set on.
    let camera = spec::CAMERA.to_vec();
    let coords = [spec::MODE, spec::METHOD, spec::FIXED_POINT_ITERATIONS];
    let with = |extra: &[SpecId]| camera.iter().chain(extra).copied().collect::<Vec<_>>();
    let warp = with(&[
        coords[0],
        coords[1],
        coords[2],
        spec::CHROMATIC,
        spec::USE_MAP,
        spec::NEAREST,
        spec::WRITE_MASK,
        spec::RECTIFY,
    ]);
    let table: Vec<(&str, &[u8], Vec<SpecId>)> = vec![
        ("points.comp", shaders::POINTS_COMP, with(&coords)),
        (
            "points.comp (forward)",
            shaders::POINTS_COMP_FORWARD,
            with(&coords[..1]),
        ),
        (
            "points.comp (forward, f64)",
            shaders::POINTS_COMP_FORWARD_F64,
            with(&coords[..1]),
        ),
        (
            "points.comp (inverse)",
            shaders::POINTS_COMP_INVERSE,
            with(&coords),
        ),
        (
            "points.comp (inverse, f64)",
            shaders::POINTS_COMP_INVERSE_F64,
            with(&coords),
        ),
        ("warp.comp", shaders::WARP_COMP, warp.clone()),
        ("warp.comp (rgba8)", shaders::WARP_COMP_RGBA8, warp.clone()),
        (
            "warp.comp (forward)",
            shaders::WARP_COMP_FORWARD,
            warp.clone(),
        ),
        (
            "warp.comp (rgba8, forward)",
            shaders::WARP_COMP_RGBA8_FORWARD,
            warp,
        ),
        (
            "warp_raster.frag",
            shaders::WARP_RASTER_FRAG,
            vec![spec::CHROMATIC, spec::NEAREST],
        ),
        (
            "inverse_map.comp",
            shaders::INVERSE_MAP_COMP,
            vec![spec::STRIDE, spec::RECTIFY],
        ),
        (
            "upsample_map.comp",
            shaders::UPSAMPLE_MAP_COMP,
            vec![
                spec::STRIDE,
                spec::REFINE,
                spec::MAX_RESIDUAL_PX,
                spec::CHECK_RESIDUAL,
                spec::CUBIC,
            ],
        ),
        (
            "geometry.vert",
            shaders::GEOMETRY_VERT,
            with(&[spec::DISTORT, spec::WRITE_FLOW, spec::READOUT]),
        ),
        (
            "geometry.vert (pinhole)",
            shaders::GEOMETRY_VERT_PINHOLE,
            with(&[spec::DISTORT, spec::WRITE_FLOW, spec::READOUT]),
        ),
        (
            "geometry.vert (global)",
            shaders::GEOMETRY_VERT_GLOBAL,
            with(&[spec::DISTORT, spec::WRITE_FLOW, spec::READOUT]),
        ),
        (
            "geometry.vert (plain)",
            shaders::GEOMETRY_VERT_PLAIN,
            vec![spec::DISTORT, spec::WRITE_FLOW],
        ),
        (
            "geometry.vert (pulled, flow)",
            shaders::GEOMETRY_VERT_PULLED_FLOW,
            with(&[spec::DISTORT, spec::WRITE_FLOW, spec::READOUT]),
        ),
        (
            "discard.comp",
            shaders::DISCARD_COMP,
            with(&[
                spec::DISTORT,
                spec::DISCARD_STAGE,
                spec::WRITE_FLOW,
                spec::READOUT,
            ]),
        ),
        (
            "discard.comp (bounded)",
            shaders::DISCARD_COMP_BOUNDED,
            with(&[
                spec::DISTORT,
                spec::DISCARD_STAGE,
                spec::WRITE_FLOW,
                spec::READOUT,
            ]),
        ),
        (
            "discard.comp (global)",
            shaders::DISCARD_COMP_GLOBAL,
            with(&[
                spec::DISTORT,
                spec::DISCARD_STAGE,
                spec::WRITE_FLOW,
                spec::READOUT,
            ]),
        ),
        (
            "discard.comp (indices)",
            shaders::DISCARD_COMP_INDICES,
            with(&[
                spec::DISTORT,
                spec::DISCARD_STAGE,
                spec::WRITE_FLOW,
                spec::READOUT,
            ]),
        ),
        (
            "geometry.frag",
            shaders::GEOMETRY_FRAG,
            vec![
                spec::WRITE_COLOR,
                spec::WRITE_IDS,
                spec::WRITE_FLOW,
                spec::WRITE_DEPTH,
            ],
        ),
        (
            "grid_demo.comp",
            shaders::GRID_DEMO_COMP,
            with(&[spec::GRID]),
        ),
        (
            "mesh_warp.frag",
            shaders::MESH_WARP_FRAG,
            vec![spec::WRITE_COORDINATES],
        ),
    ];
    for (shader, spirv, ids) in table {
        let declared = reflect::spec_constants(spirv);
        for id in ids {
            assert!(
                declared.iter().any(|(n, i)| n == id.name && *i == id.id),
                "{} (id {}) missing from {shader}: {declared:?}",
                id.name,
                id.id
            );
        }
    }
}

#[test]
fn geometry_frame_matches_the_glsl_block() {
    use crate::pass::geometry::{GeometryFrame, MotionGpu};
    let host = vec![
        (
            "view_projection",
            offset_of!(GeometryFrame, view_projection),
        ),
        (
            "previous_view_projection",
            offset_of!(GeometryFrame, previous_view_projection),
        ),
        ("view", offset_of!(GeometryFrame, view)),
        ("viewport", offset_of!(GeometryFrame, viewport)),
        ("projection", offset_of!(GeometryFrame, projection)),
        ("previous_view", offset_of!(GeometryFrame, previous_view)),
        ("motion", offset_of!(GeometryFrame, motion)),
        (
            "previous_motion",
            offset_of!(GeometryFrame, previous_motion),
        ),
        ("readout_bound", offset_of!(GeometryFrame, readout_bound)),
    ];
    let motion = vec![
        ("rotation", offset_of!(MotionGpu, rotation)),
        ("turn", offset_of!(MotionGpu, turn)),
        ("centre", offset_of!(MotionGpu, centre)),
        ("travel", offset_of!(MotionGpu, travel)),
    ];
    // The block holds every member but the rate table as one struct (the shaders copy it out
    // at the top of main()), then the rate table.
    let block = vec![
        ("values", 0),
        ("readout_rates", offset_of!(GeometryFrame, readout_rates)),
    ];
    for spirv in [
        shaders::GEOMETRY_VERT,
        shaders::DISCARD_COMP,
        shaders::DISCARD_COMP_BOUNDED,
        shaders::GEOMETRY_GEOM,
    ] {
        check(spirv, "VklFrame", host.clone());
        check(spirv, "VklMotionBlock", motion.clone());
        check(spirv, "GeometryFrame", block.clone());
    }
    // The vertex shader also reads the camera, with the same layout as everywhere.
    check_camera!(shaders::GEOMETRY_VERT, "CameraParams", CameraParams);
}

#[test]
fn discard_push_matches_the_glsl_block() {
    use crate::pass::geometry::DiscardPush;
    check(
        shaders::DISCARD_COMP,
        "DiscardPush",
        vec![("count", offset_of!(DiscardPush, count))],
    );
    assert_eq!(std::mem::size_of::<DiscardPush>(), 4);
}

#[test]
fn warp_push_matches_the_warp_and_map_blocks() {
    // One Rust struct for the warp's push constants and the map builds' (the map builds name
    // the fill slot `unused`).
    use crate::pass::warp::WarpPush;
    let warp = vec![
        ("ideal", offset_of!(WarpPush, ideal)),
        ("chromatic", offset_of!(WarpPush, chromatic)),
        ("fill", offset_of!(WarpPush, fill)),
        ("sizes", offset_of!(WarpPush, sizes)),
        ("rectify", offset_of!(WarpPush, rectify)),
    ];
    // The map builds' block ends before the warp's band.
    let mut map = warp.clone();
    map[2].0 = "unused";
    let mut warp = warp;
    warp.push(("band", offset_of!(WarpPush, band)));
    check(shaders::WARP_COMP, "WarpPush", warp.clone());
    check(shaders::WARP_COMP_RGBA8, "WarpPush", warp.clone());
    check(shaders::WARP_RASTER_FRAG, "WarpPush", warp.clone());
    check(shaders::INVERSE_MAP_COMP, "MapPush", map.clone());
    check(shaders::UPSAMPLE_MAP_COMP, "MapPush", map.clone());
    // The per-model modules the passes build from hold the same blocks.
    for spirv in shaders::WARP_COMP_BY_MODEL
        .iter()
        .chain(&shaders::WARP_COMP_RGBA8_BY_MODEL)
        .chain(&shaders::WARP_COMP_FORWARD_BY_MODEL)
        .chain(&shaders::WARP_COMP_RGBA8_FORWARD_BY_MODEL)
        .chain(&shaders::WARP_COMP_R32UI_BY_MODEL)
        .chain(&shaders::WARP_COMP_R32F_BY_MODEL)
    {
        check(spirv, "WarpPush", warp.clone());
    }
    for spirv in shaders::INVERSE_MAP_COMP_BY_MODEL
        .iter()
        .chain(&shaders::UPSAMPLE_MAP_COMP_BY_MODEL)
    {
        check(spirv, "MapPush", map.clone());
    }
    assert!(
        std::mem::size_of::<WarpPush>() <= 128,
        "past the guaranteed push-constant size"
    );
}

#[test]
fn mesh_warp_push_matches_the_glsl_block() {
    use crate::pass::mesh_warp::MeshWarpPush;
    let host = vec![("sizes", offset_of!(MeshWarpPush, sizes))];
    check(shaders::MESH_WARP_VERT, "MeshWarpPush", host.clone());
    check(shaders::MESH_WARP_FRAG, "MeshWarpPush", host);
}

#[test]
fn film_push_matches_the_glsl_block() {
    use crate::pass::film::FilmPush;
    let host = vec![
        ("film_size", offset_of!(FilmPush, film_size)),
        ("channel_mask", offset_of!(FilmPush, channel_mask)),
    ];
    check(shaders::FILM_MORPH_VERT, "FilmPush", host.clone());
    check(shaders::FILM_MORPH_FRAG, "FilmPush", host);
    assert_eq!(std::mem::size_of::<FilmPush>(), 32);
}

#[test]
fn the_geometry_path_compiles_unasked_outputs_and_terms_out() {
    // Simulate only what is asked for: a k1 k2 camera rendering colour only builds a vertex
    // stage with the rational/prism/tilt groups off and a fragment stage that writes no ID,
    // flow or depth.
    use crate::pass::geometry::{GeometryDesc, GeometryPass, Outputs, Projection};
    use ash::vk;
    let ctx = crate::host::Context::new(crate::host::ContextOptions {
        validation: true,
        device: None,
        geometry_shader: true,
        geometry_shader_discard: false,
        pipeline_cache: None,
    })
    .unwrap();
    let camera = crate::model::Camera::from_coeffs(
        640,
        480,
        crate::model::Intrinsics {
            fx: 500.0,
            fy: 500.0,
            cx: 319.5,
            cy: 239.5,
        },
        &[-0.2, 0.05, 0.0, 0.0],
    )
    .unwrap();
    let pass = GeometryPass::new(
        ctx.gpu(),
        GeometryDesc::new(camera, Projection::Lens { delta: 0.1 }, Outputs::COLOR),
    )
    .unwrap();
    let stages = &pass.pipeline().constants;
    let get = |stage: vk::ShaderStageFlags, id: SpecId| {
        stages
            .iter()
            .find(|(s, _)| *s == stage)
            .and_then(|(_, c)| c.get(id))
    };
    let v = vk::ShaderStageFlags::VERTEX;
    assert_eq!(get(v, spec::RADIAL), Some(1), "radial on");
    for id in [spec::RATIONAL, spec::TANGENTIAL, spec::PRISM, spec::TILT] {
        assert_eq!(get(v, id), Some(0), "{} compiled out", id.name);
    }
    let f = vk::ShaderStageFlags::FRAGMENT;
    assert_eq!(get(f, spec::WRITE_COLOR), Some(1));
    for id in [spec::WRITE_IDS, spec::WRITE_FLOW, spec::WRITE_DEPTH] {
        assert_eq!(get(f, id), Some(0), "{} compiled out", id.name);
    }
    // The default discard runs by compute: no geometry stage, and its per-vertex pass is
    // specialized like the vertex shader (flow off: the previous pose is never evaluated).
    assert!(!stages
        .iter()
        .any(|(s, _)| *s == vk::ShaderStageFlags::GEOMETRY));
    let [per_vertex, restore, drop] = pass.discard_constants().expect("the compute discard");
    assert_eq!(per_vertex.get(spec::RADIAL), Some(1));
    for id in [
        spec::RATIONAL,
        spec::TANGENTIAL,
        spec::PRISM,
        spec::TILT,
        spec::WRITE_FLOW,
    ] {
        assert_eq!(per_vertex.get(id), Some(0), "{} compiled out", id.name);
    }
    assert_eq!(
        get(v, spec::WRITE_FLOW),
        Some(0),
        "no previous pose in the vertex shader"
    );
    // A global shutter (no readout): the rolling shutter's per-vertex solve is compiled out
    // of both the vertex shader and the discard.
    assert_eq!(get(v, spec::READOUT), Some(0), "no rolling-shutter solve");
    assert_eq!(per_vertex.get(spec::READOUT), Some(0));
    assert_eq!(
        [per_vertex, restore, drop].map(|c| c.get(spec::DISCARD_STAGE)),
        [Some(0), Some(1), Some(2)]
    );
    // Its Sec. 3.2 bound lies well inside this lens's domain: the table lookup is compiled
    // out of the per-vertex pass (and only there).
    assert_eq!(per_vertex.get(spec::DOMAIN_TABLE), Some(0));
    assert_eq!(get(v, spec::DOMAIN_TABLE), Some(1));
    // The geometry shader, when asked for, replaces it.
    let mut desc = GeometryDesc::new(
        pass.desc().camera.clone(),
        Projection::Lens { delta: 0.1 },
        Outputs::COLOR,
    );
    desc.discard = crate::pass::geometry::Discard::GeometryShader;
    let gs = GeometryPass::new(ctx.gpu(), desc).unwrap();
    assert!(gs
        .pipeline()
        .constants
        .iter()
        .any(|(s, _)| *s == vk::ShaderStageFlags::GEOMETRY));
    assert!(gs.discard_constants().is_none());
    ctx.check_validation().unwrap();
}

#[test]
fn the_discard_leaves_the_domain_table_out_only_where_its_bound_needs_none() {
    use crate::model::{Camera, Intrinsics, OpenCvDistortion};
    use crate::pass::geometry::{GeometryDesc, GeometryPass, Outputs, Projection};
    let ctx = crate::host::Context::new(crate::host::ContextOptions {
        validation: true,
        device: None,
        geometry_shader: true,
        geometry_shader_discard: false,
        pipeline_cache: None,
    })
    .unwrap();
    let k = Intrinsics {
        fx: 400.0,
        fy: 400.0,
        cx: 399.5,
        cy: 299.5,
    };
    let radial = |k1: f64| {
        Camera::new(
            800,
            600,
            k,
            OpenCvDistortion {
                k1,
                ..Default::default()
            },
        )
        .unwrap()
    };
    // k1 = -0.05 never folds inside the domain's cap; k1 = -0.4 folds at r ≈ 0.91, inside
    // the image corners (r = 1.25): the same terms, so one pass could take both.
    let (mild, folding) = (radial(-0.05), radial(-0.4));
    assert_eq!(mild.terms(), folding.terms());
    let pass = |camera: &Camera| {
        let desc = GeometryDesc::new(
            camera.clone(),
            Projection::Lens { delta: 0.1 },
            Outputs::COLOR,
        );
        GeometryPass::new(ctx.gpu(), desc).unwrap()
    };
    let table = |p: &GeometryPass| p.discard_constants().unwrap()[0].get(spec::DOMAIN_TABLE);
    let (mut without, mut with) = (pass(&mild), pass(&folding));
    assert_eq!((table(&without), table(&with)), (Some(0), Some(1)));
    // A pass built without the table refuses a camera that needs it; one built with it takes
    // either.
    assert!(!without.accepts_camera(&folding));
    assert!(unsafe { without.set_camera(&folding) }.is_err());
    assert!(with.accepts_camera(&mild));
    assert!(unsafe { with.set_camera(&mild) }.is_ok());
    assert!(without.accepts_camera(&radial(-0.06)));
    ctx.check_validation().unwrap();
}

#[test]
fn a_specialization_constant_set_twice_keeps_one_entry() {
    // Vulkan refuses a specialization map that names an id twice: the last value wins.
    use crate::gpu::SpecConstants;
    let c = SpecConstants::new()
        .bool(spec::DOMAIN_TABLE, true)
        .u32(spec::NEWTON_ITERATIONS, 3)
        .bool(spec::DOMAIN_TABLE, false);
    assert_eq!(
        c.entries(),
        &[(spec::DOMAIN_TABLE.id, 0), (spec::NEWTON_ITERATIONS.id, 3)]
    );
}

/// A per-model module holds its own model's code and no other's (function names survive in
/// the SPIR-V's debug names): a standard camera's warp compiles no ray model at all.
#[test]
fn each_per_model_module_holds_its_model_alone() {
    use crate::model::ModelKind;
    let names = |spirv: &[u8], f: &str| spirv.windows(f.len()).any(|w| w == f.as_bytes());
    let standard = shaders::WARP_COMP_RGBA8_BY_MODEL[ModelKind::Standard.gpu_id() as usize];
    let ds = shaders::WARP_COMP_RGBA8_BY_MODEL[ModelKind::DoubleSphere.gpu_id() as usize];
    for f in ["vkl_ds_project", "vkl_omni_project", "vkl_ocam_unproject"] {
        assert!(!names(standard, f), "the standard model's module holds {f}");
        assert!(
            names(shaders::WARP_COMP_RGBA8, f),
            "the all-models module lacks {f}"
        );
    }
    assert!(names(ds, "vkl_ds_project") && names(ds, "vkl_ds_unproject"));
    assert!(!names(ds, "vkl_omni_project") && !names(ds, "vkl_tp_unproject"));
    assert!(standard.len() < shaders::WARP_COMP_RGBA8.len() * 2 / 3);
}

#[test]
fn the_upsampler_is_dispatched_by_the_workgroup_it_declares() {
    let [x, y] = crate::pass::warp::UPSAMPLE_GROUP;
    for module in shaders::UPSAMPLE_MAP_COMP_BY_MODEL {
        assert_eq!(reflect::local_size(module), Some([x, y, 1]));
    }
    assert_eq!(
        reflect::local_size(shaders::UPSAMPLE_MAP_COMP),
        Some([x, y, 1])
    );
}
