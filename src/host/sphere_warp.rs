//! The headless path of a 360° source: a cube map or a panorama seen through a lens, planned
//! and recorded as every scene is ([`crate::plan::Route::Environment`]), read back.

use crate::host::Context;
use crate::imaging::Raster;
use crate::model::Camera;
use crate::pass::environment::{check_environment, is_eight_bit};
use crate::pass::sphere_warp::{DataSource, SphereDataPass, SphereWarpOptions};
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

/// The IDs and depths of a cube map a renderer of your own made, through `camera`'s lens:
/// `ids` and `face_z` per face in [`crate::pass::sphere_warp::CubeFace::ALL`]'s order (+x −x +y
/// −y +z −z, each `side`² texels, rows from the top), each face's depth its z along its own
/// axis. Per output pixel the nearest ID and the depth carried onto the pixel's own ray
/// ([`crate::pass::sphere_warp::SphereDataPass`]): (IDs, z, range), each of the camera's
/// size; 0 and +inf where the lens sees nothing or the faces show nothing.
pub fn run_cube_data(
    ctx: &Context,
    camera: &Camera,
    side: u32,
    ids: &[Vec<u32>; 6],
    face_z: &[Vec<f32>; 6],
) -> Result<(Vec<u32>, Vec<f32>, Vec<f32>)> {
    use crate::pass::sphere_warp::CubeFace;
    let n = side as usize * side as usize;
    if ids.iter().any(|f| f.len() != n) || face_z.iter().any(|f| f.len() != n) {
        return Err(Error::input(format!(
            "cube faces of {side}² texels expected for the IDs and the depth"
        )));
    }
    // The texels in the order of the cube's layers.
    let (mut id_texels, mut z_texels) = (vec![0u32; 6 * n], vec![0f32; 6 * n]);
    for (k, face) in CubeFace::ALL.iter().enumerate() {
        let l = face.layer() as usize * n;
        id_texels[l..l + n].copy_from_slice(&ids[k]);
        z_texels[l..l + n].copy_from_slice(&face_z[k]);
    }
    run_data(
        ctx,
        camera,
        DataSource::Cube,
        (side, side),
        &id_texels,
        &z_texels,
    )
}

/// As [`run_cube_data`], from one image (`size`, rows from the top) of a pinhole camera at the
/// lens camera's centre along its axes ([`DataSource::Pinhole`], depth its z) or of an
/// equirectangular panorama ([`DataSource::Equirect`], depth the range).
pub fn run_image_data(
    ctx: &Context,
    camera: &Camera,
    source: DataSource,
    size: (u32, u32),
    ids: &[u32],
    depth: &[f32],
) -> Result<(Vec<u32>, Vec<f32>, Vec<f32>)> {
    let n = size.0 as usize * size.1 as usize;
    if source == DataSource::Cube || ids.len() != n || depth.len() != n {
        return Err(Error::input(format!(
            "one {}×{} image of IDs and one of depth expected",
            size.0, size.1
        )));
    }
    run_data(ctx, camera, source, size, ids, depth)
}

/// Uploads the source's IDs and depths (a cube's six layers, or one image), runs the data
/// pass once, reads (IDs, z, range) back.
fn run_data(
    ctx: &Context,
    camera: &Camera,
    source: DataSource,
    (sw, sh): (u32, u32),
    id_texels: &[u32],
    z_texels: &[f32],
) -> Result<(Vec<u32>, Vec<f32>, Vec<f32>)> {
    use crate::gpu::{record_upload, Access, Buffer, Image};
    use crate::host::readback::{Download, Left};
    use ash::vk;
    let gpu = ctx.gpu();
    let sampled = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
    let image = |name: &str, format| match source {
        DataSource::Cube => Image::new_cube(gpu, name, format, sw, sampled),
        _ => Image::new_2d(gpu, name, format, sw, sh, sampled),
    };
    let ids_source = image("data_source.ids", vk::Format::R32_UINT)?;
    let z_source = image("data_source.depth", vk::Format::R32_SFLOAT)?;
    let src = vk::BufferUsageFlags::TRANSFER_SRC;
    let up_ids = Buffer::from_pod(gpu, "data_source.ids.upload", id_texels, src)?;
    let up_z = Buffer::from_pod(gpu, "data_source.depth.upload", z_texels, src)?;
    let (w, h) = (camera.width, camera.height);
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
    let out = |name: &str, format| Image::new_2d(gpu, name, format, w, h, usage);
    let outputs = [
        out("data_source.out_ids", vk::Format::R32_UINT)?,
        out("data_source.out_z", vk::Format::R32_SFLOAT)?,
        out("data_source.out_range", vk::Format::R32_SFLOAT)?,
    ];
    let mut pass = SphereDataPass::new(gpu, camera, source)?;
    // SAFETY: the pass is new; the views are the source's two views and three 2D storage
    // views of this device, in the layouts the submission below puts them in.
    unsafe {
        pass.bind(
            [ids_source.view, z_source.view],
            outputs.each_ref().map(|o| o.view),
        )
    };
    let downloads = outputs
        .iter()
        .map(|o| Download::new(gpu, o, "data_source.download"))
        .collect::<Result<Vec<_>>>()?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass, on
        // a graphics and compute queue; the uploads hold every layer tightly packed; nothing
        // else uses the new images; everything outlives the submission, which `submit` waits
        // for.
        unsafe {
            record_upload(gpu, cmd, &up_ids, &ids_source, Access::ComputeSampled);
            record_upload(gpu, cmd, &up_z, &z_source, Access::ComputeSampled);
            crate::gpu::record_discard_for_compute_write(gpu, cmd, outputs.iter());
            pass.record_for_readers(cmd, None);
            for (d, o) in downloads.iter().zip(&outputs) {
                d.record(gpu, cmd, o, Left::ComputeGeneral)?;
            }
        }
        Ok(())
    })?;
    Ok((
        downloads[0].read()?,
        downloads[1].read()?,
        downloads[2].read()?,
    ))
}
