//! A scene through a lens: a scene file (or the same tables built in code), planned once, then
//! rendered frame by frame on a headless device.

use std::path::Path;

use crate::labels::{FrameLabels, ObjectLabel};
use crate::plan::{load_geometry, plan, Plan, SceneFile, SceneLabels};
use crate::scene::Scene;
use crate::{Device, Error, Result};

pub use crate::imaging::Rendered;

/// One rendered frame of a scene.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Index of the pose in the scene file's poses.
    pub index: usize,
    /// The outputs the scene asked for (colour, IDs, flow, depth, range).
    pub rendered: Rendered,
    /// The labels the scene asked for (classes, boxes, keypoints).
    pub labels: FrameLabels,
    /// Wall time of the frame's GPU work (ms).
    pub ms: f64,
}

/// A scene file planned for rendering: the geometry loaded and the cheapest pipeline for what
/// it asks chosen (see [`SceneRenderer::explain`] for the route and the reasons).
///
/// ```no_run
/// let device = vklens::Device::new()?;
/// let scene = vklens::SceneRenderer::load("examples/scenes/ids_and_flow.toml")?;
/// for frame in scene.render_all(&device)? {
///     println!("frame {}: {:.1} ms", frame.index, frame.ms);
/// }
/// # Ok::<(), vklens::Error>(())
/// ```
pub struct SceneRenderer {
    scene: Scene,
    plan: Plan,
    labels: SceneLabels,
}

impl SceneRenderer {
    /// Reads a scene file (TOML; see `examples/scenes/README.md`) and plans it.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        Self::new(SceneFile::load(path.as_ref())?)
    }

    /// Parses a scene file's text; relative paths in it are resolved against `base`'s folder.
    pub fn parse(text: &str, base: impl AsRef<Path>) -> Result<Self> {
        Self::new(SceneFile::parse(text, base.as_ref())?)
    }

    /// Plans an already read scene description.
    pub(crate) fn new(file: SceneFile) -> Result<Self> {
        let scene = load_geometry(&file)?;
        let plan = plan(&file, &scene)?;
        let labels = SceneLabels::new(&file, &scene);
        Ok(SceneRenderer {
            scene,
            plan,
            labels,
        })
    }

    /// Every object of the scene with its name and class (what `objects.json` lists).
    pub fn objects(&self) -> &[ObjectLabel] {
        &self.labels.objects
    }

    /// The plan as `vklens render --explain` prints it: the route, each step with the
    /// reason it is there, the expected error against the budget.
    pub fn explain(&self) -> String {
        self.plan.explain(None, &[])
    }

    /// The largest geometric error the plan's approximations leave (output pixels), as
    /// measured while planning.
    pub fn expected_error_px(&self) -> f64 {
        self.plan.expected_error_px
    }

    /// How many poses (frames) the scene has.
    pub fn frame_count(&self) -> usize {
        self.plan.poses.len()
    }

    /// Renders the frames `frames` (pose indices), handing each to `each` as it is done.
    pub fn render(
        &self,
        device: &Device,
        frames: std::ops::Range<usize>,
        each: &mut dyn FnMut(Frame) -> Result<()>,
    ) -> Result<()> {
        if frames.end > self.frame_count() || frames.start > frames.end {
            return Err(Error::input(format!(
                "frames {}..{}: the scene has {} pose(s)",
                frames.start,
                frames.end,
                self.frame_count()
            )));
        }
        crate::host::plan::execute(
            device.context(),
            &self.plan,
            &self.scene,
            frames,
            &mut |f: crate::host::plan::Frame| {
                let labels = self
                    .labels
                    .frame(&self.plan, &self.scene, f.index, &f.rendered)?;
                // The ID and range images the labels were read from, where the scene asked
                // for the labels alone.
                let (o, mut rendered) = (self.plan.outputs, f.rendered);
                if !o.ids {
                    rendered.ids = None;
                }
                if !o.range {
                    rendered.range = None;
                }
                each(Frame {
                    index: f.index,
                    rendered,
                    labels,
                    ms: f.ms,
                })
            },
        )?;
        Ok(())
    }

    /// Renders every frame and returns them.
    pub fn render_all(&self, device: &Device) -> Result<Vec<Frame>> {
        let mut frames = Vec::with_capacity(self.frame_count());
        self.render(device, 0..self.frame_count(), &mut |f| {
            frames.push(f);
            Ok(())
        })?;
        Ok(frames)
    }
}
