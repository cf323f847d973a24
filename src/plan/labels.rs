//! A scene file's labels, frame by frame: what `[outputs]`, `[classes]` and `[[keypoints]]`
//! ask for, computed from each frame's ID and range images through the plan's camera and pose.

use super::{Plan, SceneFile};
use crate::imaging::Rendered;
use crate::labels::{self, FrameLabels, Keypoint, LabelRequest, ObjectLabel};
use crate::scene::Scene;
use crate::{Error, Result};

/// The labels a scene file asks for, and its objects with their names and classes.
#[derive(Debug, Clone)]
pub struct SceneLabels {
    /// Every object of the scene (`objects.json`).
    pub objects: Vec<ObjectLabel>,
    keypoints: Vec<Keypoint>,
    classes: bool,
    boxes: bool,
    max_error_px: f64,
}

impl SceneLabels {
    /// The labels `file` asks for of `scene` (its geometry).
    pub fn new(file: &SceneFile, scene: &Scene) -> Self {
        SceneLabels {
            objects: labels::object_labels(scene, &file.classes),
            keypoints: file.keypoints.clone(),
            classes: file.outputs.classes,
            boxes: file.outputs.boxes,
            max_error_px: file.max_error_px,
        }
    }

    /// Frame `index`'s labels, from what `plan` rendered of it. None asked: none computed.
    pub fn frame(
        &self,
        plan: &Plan,
        scene: &Scene,
        index: usize,
        rendered: &Rendered,
    ) -> Result<FrameLabels> {
        if !(self.classes || self.boxes || !self.keypoints.is_empty()) {
            return Ok(FrameLabels::default());
        }
        let view = plan.view(index).ok_or_else(|| {
            Error::internal(format!(
                "labels of frame {index} need a camera and its pose; the plan has neither"
            ))
        })?;
        labels::frame_labels(
            &view,
            scene,
            rendered,
            &LabelRequest {
                objects: &self.objects,
                classes: self.classes,
                boxes: self.boxes,
                keypoints: &self.keypoints,
                max_error_px: self.max_error_px,
            },
        )
        .map_err(Error::internal)
    }
}
