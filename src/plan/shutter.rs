//! The sensor's shutter in a plan: which readout applies and where it came from (the scene's
//! `[sensor] rolling_shutter`, else the camera file's `shutter_type`), and the refusal of what
//! the renderer cannot draw yet.
//!
//! Every route draws a frame from one pose. That is exactly a rolling shutter's image where the
//! camera does not move during the frame (every line sees the same pose); where it moves
//! (`end_rvec`, `end_tvec` differ from `rvec`, `tvec`), each line sees another pose, and
//! drawing the frame from one of them would be a global shutter's image under another name.
//! So a moving rolling shutter is refused, naming the key, never rendered as a global one.

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
}

impl Shutter {
    /// The line `--explain` prints.
    pub fn explain(self) -> String {
        match self {
            Shutter::Global => "global: every line is read at once (no [sensor] rolling_shutter, and no rolling shutter_type in a camera file)".into(),
            Shutter::Rolling { readout, from } => format!(
                "rolling, {readout}, from {}; the camera does not move during any frame (no end_rvec, end_tvec apart from rvec, tvec), so every line sees the frame's one pose and the image is the global shutter's, exactly",
                source_words(readout, from)
            ),
        }
    }

    /// The readout's name, or `global` (plan.json).
    pub fn name(self) -> &'static str {
        match self {
            Shutter::Global => "global",
            Shutter::Rolling { readout, .. } => readout.name(),
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
    }
}

/// The shutter of `file`'s frames through a camera whose file states `camera_readout` (`None`
/// for a lens prescription, which states none). Refuses a camera that moves during a frame: through a rolling shutter the
/// renderer cannot draw it yet, and through a global one the end pose contradicts the shutter.
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
        (Some((readout, from)), Some(i)) => Err(Error::unsupported(format!(
            "{src}: [sensor] rolling_shutter: the readout is {readout} (from {}), and [[poses]] #{} moves during its frame (end_rvec, end_tvec differ from rvec, tvec); the renderer draws every line of a frame from one pose, so it cannot render a moving rolling shutter yet, and will not pass a global shutter's image off as one. `vklens points project --rolling-shutter {readout}` projects points through it exactly; without end_rvec and end_tvec the frame renders still",
            source_words(readout, from),
            i + 1
        ))),
    }
}
