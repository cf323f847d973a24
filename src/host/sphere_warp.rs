//! The headless path of a 360° source: a cube map or a panorama seen through a lens, planned
//! and recorded as every scene is ([`crate::plan::Route::Environment`]), read back.

use crate::host::Context;
use crate::imaging::Raster;
use crate::model::Camera;
use crate::pass::environment::{check_environment, is_eight_bit};
use crate::pass::sphere_warp::SphereWarpOptions;
use crate::plan::{PathChoice, RenderRequest};
use crate::scene::Scene;
use crate::{Error, Result};

/// Runs the sphere warp of a scene that is a 360° image ([`Scene::from_environment`]) once
/// through a headless context: its plan ([`crate::plan::Plan::from_request_with_scene`])
/// executed, read back. The output has the camera's size, and the bit depth of the source
/// (8-bit stays 8-bit); the mask is 255 where a pixel has a source.
pub fn run_environment(
    ctx: &Context,
    camera: &Camera,
    scene: &Scene,
    options: &SphereWarpOptions,
) -> Result<(Raster, Vec<u8>)> {
    let environment = scene
        .environment
        .as_ref()
        .ok_or_else(|| Error::input(format!("{}: not a 360° image", scene.name)))?;
    // The source's own problems first: they name what to fix in it.
    check_environment(ctx.gpu(), environment)?;
    let eight_bit = is_eight_bit(environment);
    let depth = environment.rasters()[0].bit_depth;
    let mut request = RenderRequest::color(
        camera,
        PathChoice::Warp {
            method: crate::model::InverseMethod::Newton,
            density: 1.0,
        },
    );
    request.outputs.exr = !eight_bit;
    request.background = options.fill;
    request.chromatic = options.chromatic;
    let out = super::plan::render_request(ctx, scene, &request, &mut |_| {})?;
    let (Some(mut colour), Some(mask)) = (out.color, out.mask) else {
        return Err(Error::internal("the 360° plan read back no colour or mask"));
    };
    if !eight_bit {
        colour.bit_depth = depth;
    }
    Ok((colour, mask))
}
