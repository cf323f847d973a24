//! One struct, one layout: the host structs against the compiled SPIR-V's block offsets, and
//! the specialization constants the shaders declare against the ids the host sets.

use std::mem::offset_of;

use vklens::gpu::{reflect, shaders};
use vklens::pass::{CameraParams, CameraParams64, CAMERA_SPEC_IDS};

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
            ("domain", offset_of!($t, domain)),
        ]
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
    check(
        shaders::POINTS_COMP,
        "CameraParams",
        host_offsets!(CameraParams),
    );
    check(
        shaders::GRID_DEMO_COMP,
        "CameraParams",
        host_offsets!(CameraParams),
    );
}

#[test]
fn camera_params_f64_matches_the_glsl_block() {
    check(
        shaders::POINTS_COMP_F64,
        "CameraParams64",
        host_offsets!(CameraParams64),
    );
}

#[test]
fn shaders_declare_the_spec_constants_the_host_sets() {
    let declared = reflect::spec_constants(shaders::POINTS_COMP);
    for (name, id) in CAMERA_SPEC_IDS {
        assert!(
            declared.iter().any(|(n, i)| n == name && *i == id),
            "{name} (id {id}) missing from points.comp: {declared:?}"
        );
    }
}
