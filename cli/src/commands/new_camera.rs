//! `vklens new-camera`: the pinhole camera to undistort into, chosen as OpenCV chooses it; and
//! the same choice for `vklens undistort` (`--alpha`, `--balance`).

use std::path::PathBuf;

use clap::Args;

use super::CliError;
use vklens::model::new_camera::{fisheye_new_camera, optimal_new_camera, Roi};
use vklens::model::Camera;

/// How the new pinhole camera is chosen: OpenCV's `getOptimalNewCameraMatrix` (`--alpha`, the
/// standard model) or `fisheye.estimateNewCameraMatrixForUndistortRectify` (`--balance`, the
/// fisheye model).
#[derive(Args, Debug, Clone, Default)]
pub struct RuleArgs {
    /// OpenCV's standard model (and Brown's): the camera cv2.getOptimalNewCameraMatrix picks.
    /// 0 keeps only pixels that have a source (no black border, the lens's edges cropped); 1
    /// keeps every source pixel (black where the undistorted image has no source); between,
    /// a blend of the two. Uses vklens's converged inverse, where OpenCV stops after 5
    /// iterations (the cameras differ slightly on a strong lens).
    #[arg(long, value_name = "A", conflicts_with = "balance")]
    pub alpha: Option<f64>,
    /// OpenCV's fisheye model: the camera cv2.fisheye.estimateNewCameraMatrixForUndistortRectify
    /// picks (R = identity). 0: the largest focal length that the four edge midpoints allow
    /// (cropped), 1: the smallest (every edge midpoint in the image).
    #[arg(long, value_name = "B")]
    pub balance: Option<f64>,
    /// With --balance: divide the new focal length by F (2 shows twice the field; OpenCV's
    /// fov_scale). Default 1.
    #[arg(long, value_name = "F", requires = "balance")]
    pub fov_scale: Option<f64>,
    /// The new image's size, as WIDTHxHEIGHT (OpenCV's newImgSize / new_size); default: the
    /// camera's own.
    #[arg(long, value_name = "WxH", value_parser = parse_new_size)]
    pub new_size: Option<(u32, u32)>,
    /// With --alpha: put the principal point at the new image's centre and scale the focal
    /// lengths alone (OpenCV's centerPrincipalPoint).
    #[arg(long, conflicts_with = "balance")]
    pub center_principal_point: bool,
}

fn parse_new_size(s: &str) -> Result<(u32, u32), String> {
    vklens::io::catalog::parse_size(s).map_err(|e| e.message_only())
}

impl RuleArgs {
    /// Whether a rule was asked for.
    pub fn given(&self) -> bool {
        self.alpha.is_some() || self.balance.is_some()
    }

    /// Whether any of these flags was given.
    pub fn any(&self) -> bool {
        self.given() || self.new_size.is_some() || self.center_principal_point
    }

    /// The new camera and its valid ROI, with a line saying which rule chose it; `None` when
    /// no rule was asked for (a --new-size alone is refused).
    pub fn choose(&self, camera: &Camera) -> Result<Option<(Camera, Roi, String)>, CliError> {
        let size = self
            .new_size
            .map(|(w, h)| format!(", new size {w}×{h}"))
            .unwrap_or_default();
        if let Some(alpha) = self.alpha {
            let (new, roi) =
                optimal_new_camera(camera, alpha, self.new_size, self.center_principal_point)?;
            let centred = if self.center_principal_point {
                ", principal point centred"
            } else {
                ""
            };
            let rule =
                format!("cv2.getOptimalNewCameraMatrix's rule, alpha {alpha}{size}{centred}");
            return Ok(Some((new, roi, rule)));
        }
        if let Some(balance) = self.balance {
            let fov_scale = self.fov_scale.unwrap_or(1.0);
            let (new, roi) = fisheye_new_camera(camera, balance, fov_scale, self.new_size)?;
            let rule = format!(
                "cv2.fisheye.estimateNewCameraMatrixForUndistortRectify's rule, balance {balance}, fov_scale {fov_scale}{size}"
            );
            return Ok(Some((new, roi, rule)));
        }
        if self.center_principal_point {
            return Err(CliError::input(
                "--center-principal-point centres the camera that --alpha chooses (OpenCV's centerPrincipalPoint): give --alpha",
            ));
        }
        if self.new_size.is_some() {
            return Err(CliError::input(
                "--new-size sizes the camera that --alpha (OpenCV's standard model) or --balance (its fisheye model) chooses: give one of them",
            ));
        }
        Ok(None)
    }
}

/// `vklens new-camera`.
#[derive(Args, Debug)]
pub struct NewCameraArgs {
    /// The lens (any camera file vklens reads).
    #[arg(long, value_name = "CAM")]
    camera: PathBuf,
    #[command(flatten)]
    rule: RuleArgs,
}

/// The line that says which output camera a warp uses.
pub fn describe(new: &Camera, roi: Roi, rule: &str) -> String {
    let k = new.intrinsics;
    format!(
        "output camera ({rule}): {}×{} pinhole, fx {} fy {} cx {} cy {}; valid ROI x {} y {} w {} h {}",
        new.width, new.height, k.fx, k.fy, k.cx, k.cy, roi.0, roi.1, roi.2, roi.3
    )
}

/// Prints `{"camera": {...}, "roi": [x, y, w, h]}`.
pub fn run(args: NewCameraArgs) -> Result<(), CliError> {
    if !args.rule.given() {
        return Err(CliError::input(
            "give --alpha A (OpenCV's standard model: cv2.getOptimalNewCameraMatrix) or --balance B (its fisheye model: cv2.fisheye.estimateNewCameraMatrixForUndistortRectify)",
        ));
    }
    let camera = super::load_camera(&args.camera)?;
    let Some((new, roi, _)) = args.rule.choose(&camera)? else {
        return Err(CliError::internal(
            "a rule was given but none chose a camera",
        ));
    };
    let json = serde_json::json!({
        "camera": new.to_json(),
        "roi": [roi.0, roi.1, roi.2, roi.3],
    });
    outln!("{json}")?;
    Ok(())
}
