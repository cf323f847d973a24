//! The sensor's shutter in a plan: which readout applies and where it came from (the scene's
//! `[sensor] rolling_shutter`, else the camera file's `shutter_type`), and the refusal of what
//! the renderer cannot draw yet.
//!
//! Where the camera does not move during a frame, every line sees the same pose and a rolling
//! shutter's image is the global shutter's, exactly: every route draws it. Where it moves
//! (`end_rvec`, `end_tvec` differ from `rvec`, `tvec`), each line sees another pose. The vertex
//! path draws that exactly, solving per vertex the readout time at which its own line reads it
//! (`glsl/include/rolling_shutter.glsl`). The warp and the cube map draw a frame from one
//! pose; they approximate the motion in bands of lines, each rendered from the pose of its
//! middle line (`model::rolling_shutter::bands`), where the error that leaves meets the budget
//! (the choice is `choice::choose_moving_rolling_shutter`). The image-based lens model draws
//! from one pose only, so a lens prescription is refused, naming the key.

use super::SceneFile;
use crate::model::rolling_shutter::Readout;
use crate::{Error, Result};

/// Where a plan's readout came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReadoutSource {
    /// The scene file's `[sensor] rolling_shutter`.
    SceneKey,
    /// The camera file's `shutter_type` (NCore's).
    CameraFile,
    /// A render request's own (`vklens render --rolling-shutter`, or the camera file's
    /// `shutter_type` it defaulted to).
    Request,
}

/// The shutter a plan's frames are rendered with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Shutter {
    /// Every line read at once.
    #[default]
    Global,
    /// Lines read one after another, the camera still during every frame.
    Rolling {
        readout: Readout,
        from: ReadoutSource,
    },
    /// Lines read one after another, the camera moving during frame `frame` (the first that
    /// moves, counted from 0) and maybe others: each line sees its own pose.
    Moving {
        readout: Readout,
        from: ReadoutSource,
        frame: usize,
    },
}

impl Shutter {
    /// The line `--explain` prints; `bands`: the plan draws a moving frame by the warp in that
    /// many bands of lines (`None`: exactly, per vertex).
    pub fn explain(self, bands: Option<u32>) -> String {
        let drawn = match bands {
            Some(k) => format!("approximated by the warp in {k} bands of lines, each from the pose of its middle line"),
            None => "drawn exactly per vertex".into(),
        };
        match self {
            Shutter::Global => "global: every line is read at once (no [sensor] rolling_shutter, and no rolling shutter_type in a camera file)".into(),
            Shutter::Rolling { readout, from } => format!(
                "rolling, {readout}, from {}; the camera does not move during any frame (no end_rvec, end_tvec apart from rvec, tvec), so every line sees the frame's one pose and the image is the global shutter's, exactly",
                source_words(readout, from)
            ),
            Shutter::Moving { readout, from, frame } => format!(
                "rolling, {readout}, from {}; the camera moves during frame {} (end_rvec, end_tvec apart from rvec, tvec), so each line sees the pose of its own readout time (slerp and a linear centre between the two poses), {drawn}",
                source_words(readout, from),
                frame + 1
            ),
        }
    }

    /// The readout of a camera that moves during a frame (what the vertex path solves per
    /// vertex); `None` where every line of every frame sees one pose.
    pub fn moving_readout(self) -> Option<Readout> {
        match self {
            Shutter::Moving { readout, .. } => Some(readout),
            _ => None,
        }
    }

    /// The refusal of a route that draws each frame from one pose, where the camera moves
    /// during a frame: `route` names it, `why` says why the plan needed it.
    pub(super) fn refuse_one_pose_route(self, source: &str, route: &str, why: &str) -> Result<()> {
        let Shutter::Moving {
            readout,
            from,
            frame,
        } = self
        else {
            return Ok(());
        };
        Err(Error::unsupported(format!(
            "{source}: [sensor] rolling_shutter: the readout is {readout} (from {}) and [[poses]] #{} moves during its frame, which only the vertex path draws (each vertex where its own line reads it); {why}, and {route} draws a frame from one pose, so it would render a global shutter's image under another name. Drop what needs it, or drop end_rvec and end_tvec to render the frame still",
            source_words(readout, from),
            frame + 1
        )))
    }

    /// The readout's name, or `global` (plan.json).
    pub fn name(self) -> &'static str {
        match self {
            Shutter::Global => "global",
            Shutter::Rolling { readout, .. } | Shutter::Moving { readout, .. } => readout.name(),
        }
    }
}

fn source_words(readout: Readout, from: ReadoutSource) -> String {
    match from {
        ReadoutSource::SceneKey => "[sensor] rolling_shutter".into(),
        ReadoutSource::CameraFile => format!(
            "the camera file's shutter_type {} ([sensor] rolling_shutter overrides it)",
            readout.ncore_name()
        ),
        ReadoutSource::Request => {
            "the request (--rolling-shutter, else the camera file's shutter_type)".into()
        }
    }
}

/// The shutter of `file`'s frames through a camera whose file states `camera_readout` (`None`
/// for a lens prescription, which states none). Refuses a camera that moves during a frame
/// through a global shutter: the end pose contradicts the shutter.
pub(super) fn resolve(file: &SceneFile, camera_readout: Option<Readout>) -> Result<Shutter> {
    let src = file.source.display();
    let readout = match (file.sensor.rolling_shutter, camera_readout) {
        (Some(r), _) => Some((r, ReadoutSource::SceneKey)),
        (None, Some(r)) => Some((r, ReadoutSource::CameraFile)),
        (None, None) => None,
    };
    let moving = file
        .poses
        .iter()
        .zip(&file.end_poses)
        .position(|(start, end)| end.is_some_and(|end| end != *start));
    match (readout, moving) {
        (None, None) => Ok(Shutter::Global),
        (Some((readout, from)), None) => Ok(Shutter::Rolling { readout, from }),
        (None, Some(i)) => Err(Error::input(format!(
            "{src}: [[poses]] #{}.end_rvec: the camera moves during the frame (end_rvec, end_tvec differ from rvec, tvec), but the shutter is global: every line is read at once, from rvec, tvec. Give [sensor] rolling_shutter (top_to_bottom, bottom_to_top, left_to_right or right_to_left), or drop end_rvec and end_tvec",
            i + 1
        ))),
        (Some((readout, from)), Some(frame)) => Ok(Shutter::Moving {
            readout,
            from,
            frame,
        }),
    }
}
