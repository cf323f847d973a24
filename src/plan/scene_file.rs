//! The scene file (TOML): what to render, through which optics, which effects and outputs
//! are wanted, and how accurate the geometry must be. Every key is documented in
//! `examples/scenes/README.md`; errors name the file, the key and what was expected. Unknown
//! keys are errors too (a typo must not silently switch an effect off).

use std::path::{Path, PathBuf};

use glam::DVec3;
use toml::{Table, Value};

use crate::model::rolling_shutter::Readout;
use crate::scene::Pose;

/// The accuracy budget (largest geometric error in output pixels) where none is given: a
/// scene file's `[accuracy] max_error_px`, and `vklens render --max-error-px`.
pub const DEFAULT_MAX_ERROR_PX: f64 = 0.01;

/// What is wrong with a scene file: one line, `file: [table] key: problem`.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneFileError {
    pub file: String,
    pub key: String,
    pub problem: String,
}

impl std::fmt::Display for SceneFileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.file, self.problem)
        } else {
            write!(f, "{}: {}: {}", self.file, self.key, self.problem)
        }
    }
}

impl std::error::Error for SceneFileError {}

/// The optics: a calibrated camera, or a lens prescription.
#[derive(Debug, Clone, PartialEq)]
pub enum OpticsSpec {
    /// An OpenCV / ROS / vklens camera file.
    Camera(PathBuf),
    /// A lens file with its setting and film.
    Lens {
        path: PathBuf,
        /// Metres from the front vertex; `None`: the scene's centre.
        focus_m: Option<f64>,
        f_number: Option<f64>,
        sensor_mm: (f64, f64),
        pixels: (u32, u32),
    },
}

/// The effects the scene asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Effects {
    pub distortion: bool,
    pub chromatic_aberration: bool,
    /// Camera files: the per-channel radial scales (R, G, B) of the lateral colour.
    pub chromatic_scales: [f64; 3],
    pub vignetting: bool,
    pub depth_of_field: bool,
    /// Lens samples for depth of field.
    pub lens_samples: u32,
}

/// The outputs the scene asks for.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OutputSpec {
    pub color: bool,
    pub ids: bool,
    pub flow: bool,
    /// Camera-frame z (metres).
    pub depth: bool,
    /// Distance from the projection centre along each pixel's ray (metres).
    pub range: bool,
    /// Class IDs (16-bit PNG): each object's class by the scene's `[classes]` patterns.
    pub classes: bool,
    /// Each visible object's boxes and 3D box corners through the lens (JSON).
    pub boxes: bool,
    /// The scene names keypoints (`[[keypoints]]`): their pixels and visibility (JSON).
    pub keypoints: bool,
    /// Colour as float EXR instead of 8-bit PNG.
    pub exr: bool,
}

impl OutputSpec {
    /// Whether the object ID image is rendered: asked for, or what classes and boxes are
    /// read from.
    pub fn renders_ids(&self) -> bool {
        self.ids || self.classes || self.boxes
    }

    /// Whether the range image is rendered: asked for, or what boxes' corners and keypoints
    /// are tested against for occlusion.
    pub fn renders_range(&self) -> bool {
        self.range || self.boxes || self.keypoints
    }

    /// Whether any per-pixel data beside colour is rendered (IDs, flow, depth or range):
    /// none of it may be filtered, and a cube map carries colour alone.
    pub fn renders_data(&self) -> bool {
        self.renders_ids() || self.flow || self.depth || self.renders_range()
    }

    /// The colour output alone, as asked (the anti-aliased pass renders nothing else).
    pub fn color_only(&self) -> OutputSpec {
        OutputSpec {
            color: self.color,
            exr: self.exr,
            ..OutputSpec::default()
        }
    }
}

/// The sensor (`[sensor]`): how it reads its lines.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SensorSpec {
    /// `rolling_shutter`: the readout the scene asks for, over the camera file's own
    /// (`shutter_type`); `None`: the camera file's, or a global shutter.
    pub rolling_shutter: Option<Readout>,
}

/// A parsed scene file.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneFile {
    /// The file it came from (errors and relative paths).
    pub source: PathBuf,
    /// A built-in scene spec or a mesh path (resolved against the file's folder).
    pub geometry: String,
    pub optics: OpticsSpec,
    pub effects: Effects,
    pub outputs: OutputSpec,
    /// The accuracy budget: largest geometric error in output pixels.
    pub max_error_px: f64,
    /// The poses to render; empty: the scene centred in the view. With a rolling shutter,
    /// the pose when the first line of the frame is read.
    pub poses: Vec<Pose>,
    /// One per pose: the pose when the last line of the frame is read (`end_rvec`,
    /// `end_tvec`); `None`: the camera does not move during that frame.
    pub end_poses: Vec<Option<Pose>>,
    pub sensor: SensorSpec,
    pub background: [f32; 4],
    /// Anti-aliasing of colour (`[render]`): the same meaning as `vklens render`'s flags.
    pub antialias: Antialias,
    /// `[render] path`: the path the scene asks for, as `vklens render --path` spells it;
    /// `None`: the planner's choice.
    pub path: Option<super::PathKind>,
    /// `[classes]`: object name patterns and their class IDs, in the file's order (the
    /// first match wins).
    pub classes: Vec<crate::labels::ClassRule>,
    /// `[[keypoints]]`: named world points whose pixels and visibility each frame labels.
    pub keypoints: Vec<crate::labels::Keypoint>,
}

/// Colour anti-aliasing: `supersample`× the resolution box-filtered down, `jitter` sub-sample
/// passes averaged. IDs, flow and depth are always one sample per pixel (never blended).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Antialias {
    pub supersample: u32,
    pub jitter: u32,
}

impl Default for Antialias {
    fn default() -> Self {
        Antialias {
            supersample: 1,
            jitter: 1,
        }
    }
}

impl Antialias {
    /// Whether more than one sample per pixel is asked for.
    pub fn is_on(&self) -> bool {
        *self != Antialias::default()
    }
}

struct Reader<'a> {
    file: &'a str,
}

impl Reader<'_> {
    fn err(&self, key: &str, problem: impl Into<String>) -> SceneFileError {
        SceneFileError {
            file: self.file.to_string(),
            key: key.to_string(),
            problem: problem.into(),
        }
    }

    fn table<'t>(
        &self,
        root: &'t Table,
        name: &str,
        keys: &[&str],
    ) -> Result<Option<&'t Table>, SceneFileError> {
        match root.get(name) {
            None => Ok(None),
            Some(Value::Table(t)) => {
                for k in t.keys() {
                    if !keys.contains(&k.as_str()) {
                        return Err(self.err(
                            &format!("[{name}] {k}"),
                            format!("unknown key; expected one of {}", keys.join(", ")),
                        ));
                    }
                }
                Ok(Some(t))
            }
            Some(other) => Err(self.err(
                &format!("[{name}]"),
                format!("expected a table, found {}", other.type_str()),
            )),
        }
    }

    fn bool(
        &self,
        t: Option<&Table>,
        table: &str,
        key: &str,
        default: bool,
    ) -> Result<bool, SceneFileError> {
        match t.and_then(|t| t.get(key)) {
            None => Ok(default),
            Some(Value::Boolean(b)) => Ok(*b),
            Some(v) => Err(self.err(
                &format!("[{table}] {key}"),
                format!("expected true or false, found {v}"),
            )),
        }
    }

    fn number(&self, v: &Value, key: &str) -> Result<f64, SceneFileError> {
        let x = match v {
            Value::Float(f) => *f,
            Value::Integer(i) => *i as f64,
            other => {
                return Err(self.err(key, format!("expected a number, found {other}")));
            }
        };
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(key, format!("expected a finite number, found {x}")))
        }
    }

    fn opt_number(
        &self,
        t: Option<&Table>,
        table: &str,
        key: &str,
    ) -> Result<Option<f64>, SceneFileError> {
        t.and_then(|t| t.get(key))
            .map(|v| self.number(v, &format!("[{table}] {key}")))
            .transpose()
    }

    /// An optional whole number in `range` (`[table] key` in errors).
    fn opt_whole(
        &self,
        t: Option<&Table>,
        table: &str,
        key: &str,
        range: std::ops::RangeInclusive<u32>,
    ) -> Result<Option<u32>, SceneFileError> {
        match self.opt_number(t, table, key)? {
            None => Ok(None),
            Some(n)
                if n.fract() == 0.0
                    && (*range.start() as f64..=*range.end() as f64).contains(&n) =>
            {
                Ok(Some(n as u32))
            }
            Some(n) => Err(self.err(
                &format!("[{table}] {key}"),
                format!(
                    "expected a whole number {}..={}, found {n}",
                    range.start(),
                    range.end()
                ),
            )),
        }
    }

    fn numbers<const N: usize>(&self, v: &Value, key: &str) -> Result<[f64; N], SceneFileError> {
        let Value::Array(a) = v else {
            return Err(self.err(key, format!("expected an array of {N} numbers, found {v}")));
        };
        if a.len() != N {
            return Err(self.err(key, format!("expected {N} numbers, found {}", a.len())));
        }
        let mut out = [0.0; N];
        for (i, x) in a.iter().enumerate() {
            out[i] = self.number(x, key)?;
        }
        Ok(out)
    }

    fn string<'t>(
        &self,
        t: Option<&'t Table>,
        table: &str,
        key: &str,
    ) -> Result<Option<&'t str>, SceneFileError> {
        match t.and_then(|t| t.get(key)) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.as_str())),
            Some(v) => Err(self.err(
                &format!("[{table}] {key}"),
                format!("expected a string, found {v}"),
            )),
        }
    }

    fn pose(&self, v: &Value, key: &str) -> Result<Pose, SceneFileError> {
        let Value::Table(t) = v else {
            return Err(self.err(key, "expected a table with rvec and tvec"));
        };
        for k in t.keys() {
            if k != "rvec" && k != "tvec" {
                return Err(self.err(&format!("{key}.{k}"), "unknown key; expected rvec, tvec"));
            }
        }
        let get = |k: &str| {
            t.get(k)
                .ok_or_else(|| self.err(&format!("{key}.{k}"), "missing (3 numbers)"))
        };
        let r = self.numbers::<3>(get("rvec")?, &format!("{key}.rvec"))?;
        let tv = self.numbers::<3>(get("tvec")?, &format!("{key}.tvec"))?;
        Ok(Pose::from_rvec_tvec(DVec3::from(r), DVec3::from(tv)))
    }

    /// A `[[poses]]` table: `rvec`, `tvec` (the pose when the first line is read) and,
    /// together or not at all, `end_rvec`, `end_tvec` (when the last one is).
    fn frame_pose(&self, v: &Value, key: &str) -> Result<(Pose, Option<Pose>), SceneFileError> {
        let Value::Table(t) = v else {
            return Err(self.err(key, "expected a table with rvec and tvec"));
        };
        const KEYS: [&str; 4] = ["rvec", "tvec", "end_rvec", "end_tvec"];
        if let Some(k) = t.keys().find(|k| !KEYS.contains(&k.as_str())) {
            return Err(self.err(
                &format!("{key}.{k}"),
                format!("unknown key; expected {}", KEYS.join(", ")),
            ));
        }
        let mut start = t.clone();
        start.retain(|k, _| k == "rvec" || k == "tvec");
        let pose = self.pose(&Value::Table(start), key)?;
        let end = match (t.get("end_rvec"), t.get("end_tvec")) {
            (None, None) => None,
            (Some(r), Some(tv)) => {
                let r = self.numbers::<3>(r, &format!("{key}.end_rvec"))?;
                let tv = self.numbers::<3>(tv, &format!("{key}.end_tvec"))?;
                Some(Pose::from_rvec_tvec(DVec3::from(r), DVec3::from(tv)))
            }
            (given, _) => {
                let (has, missing) = if given.is_some() {
                    ("end_rvec", "end_tvec")
                } else {
                    ("end_tvec", "end_rvec")
                };
                return Err(self.err(
                    &format!("{key}.{missing}"),
                    format!("missing beside {has}: end_rvec and end_tvec come together (the pose when the last line of the frame is read)"),
                ));
            }
        };
        Ok((pose, end))
    }
}

impl SceneFile {
    /// Reads and checks a scene file.
    pub fn load(path: &Path) -> Result<Self, SceneFileError> {
        let file = path.display().to_string();
        let text = crate::io::read_text(path).map_err(|e| SceneFileError {
            file: file.clone(),
            key: String::new(),
            problem: format!("cannot read: {e}"),
        })?;
        Self::parse(&text, path)
    }

    /// Parses the text of a scene file that lives at `path`.
    pub fn parse(text: &str, path: &Path) -> Result<Self, SceneFileError> {
        let file = path.display().to_string();
        let r = Reader { file: &file };
        let root: Table = text
            .parse()
            .map_err(|e: toml::de::Error| r.err("", format!("not valid TOML: {}", e.message())))?;
        const TABLES: [&str; 11] = [
            "geometry",
            "optics",
            "sensor",
            "effects",
            "outputs",
            "accuracy",
            "poses",
            "pose_sequence",
            "render",
            "classes",
            "keypoints",
        ];
        for k in root.keys() {
            if !TABLES.contains(&k.as_str()) {
                return Err(r.err(
                    k,
                    format!("unknown key; expected one of {}", TABLES.join(", ")),
                ));
            }
        }
        let dir = path.parent().unwrap_or(Path::new("."));
        // Table by table in the documentation's order, so that a file with several mistakes
        // is told about the first.
        let geometry = r.geometry(&root, dir)?;
        let optics = r.optics(&root, dir)?;
        let effects = r.effects(&root, &optics)?;
        let mut outputs = r.outputs(&root)?;
        let classes = r.classes(&root)?;
        let keypoints = r.keypoints(&root)?;
        outputs.keypoints = !keypoints.is_empty();
        let max_error_px = r.accuracy(&root)?;
        let (background, antialias, asked_path) = r.render(&root)?;
        let sensor = r.sensor(&root)?;
        let (poses, end_poses) = r.poses(&root)?;
        Ok(SceneFile {
            source: path.to_path_buf(),
            geometry,
            optics,
            effects,
            outputs,
            max_error_px,
            poses,
            end_poses,
            sensor,
            background,
            antialias,
            path: asked_path,
            classes,
            keypoints,
        })
    }
}

/// `p` relative to the scene file's folder `dir`, unless absolute.
fn resolve(dir: &Path, p: &str) -> PathBuf {
    let p = Path::new(p);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        dir.join(p)
    }
}

/// One reader per table of the scene file, in the order the file's documentation lists them.
impl Reader<'_> {
    /// `[geometry]`: a built-in scene or a mesh file.
    fn geometry(&self, root: &Table, dir: &Path) -> Result<String, SceneFileError> {
        let geometry = self.table(root, "geometry", &["scene"])?;
        let scene = self.string(geometry, "geometry", "scene")?.ok_or_else(|| {
            self.err(
                "[geometry] scene",
                "missing: a built-in scene (checkerboard, grid, boxes, room) or a mesh file",
            )
        })?;
        let builtin = ["checkerboard", "grid", "boxes", "room"]
            .iter()
            .any(|b| scene == *b || scene.starts_with(&format!("{b}:")));
        let geometry = if builtin {
            scene.to_string()
        } else {
            resolve(dir, scene).display().to_string()
        };
        Ok(geometry)
    }

    /// `[optics]`: a camera file or a lens prescription with its film and focus.
    fn optics(&self, root: &Table, dir: &Path) -> Result<OpticsSpec, SceneFileError> {
        let optics_t = self.table(
            root,
            "optics",
            &["camera", "lens", "focus_m", "fstop", "sensor_mm", "pixels"],
        )?;
        let camera = self.string(optics_t, "optics", "camera")?;
        let lens = self.string(optics_t, "optics", "lens")?;
        let optics = match (camera, lens) {
            (Some(_), Some(_)) => {
                return Err(self.err("[optics]", "give camera or lens, not both"));
            }
            (None, None) => {
                return Err(self.err(
                "[optics]",
                "missing: camera = \"CAM.yml\" (a calibrated camera) or lens = \"LENS.dat\" (a prescription)",
            ));
            }
            (Some(c), None) => {
                for k in ["focus_m", "fstop", "sensor_mm", "pixels"] {
                    if optics_t.is_some_and(|t| t.contains_key(k)) {
                        return Err(self.err(
                            &format!("[optics] {k}"),
                            "only for a lens prescription (the camera file fixes its own)",
                        ));
                    }
                }
                OpticsSpec::Camera(resolve(dir, c))
            }
            (None, Some(l)) => {
                let focus_m = self.opt_number(optics_t, "optics", "focus_m")?;
                if let Some(f) = focus_m {
                    if !(f > 0.0) {
                        return Err(self.err(
                            "[optics] focus_m",
                            format!("expected metres > 0, found {f}"),
                        ));
                    }
                }
                let f_number = self.opt_number(optics_t, "optics", "fstop")?;
                let sensor = match optics_t.and_then(|t| t.get("sensor_mm")) {
                    Some(v) => self.numbers::<2>(v, "[optics] sensor_mm")?,
                    None => [36.0, 24.0],
                };
                if !(sensor[0] > 0.0 && sensor[1] > 0.0) {
                    return Err(self.err("[optics] sensor_mm", "expected two positive sizes in mm"));
                }
                let pixels = match optics_t.and_then(|t| t.get("pixels")) {
                    Some(v) => self.numbers::<2>(v, "[optics] pixels")?,
                    None => [480.0, 320.0],
                };
                if !pixels
                    .iter()
                    .all(|p| p.fract() == 0.0 && (1.0..=16384.0).contains(p))
                {
                    return Err(
                        self.err("[optics] pixels", "expected two whole numbers in 1..=16384")
                    );
                }
                OpticsSpec::Lens {
                    path: resolve(dir, l),
                    focus_m,
                    f_number,
                    sensor_mm: (sensor[0], sensor[1]),
                    pixels: (pixels[0] as u32, pixels[1] as u32),
                }
            }
        };
        Ok(optics)
    }

    /// `[effects]`, checked against the optics.
    fn effects(&self, root: &Table, optics: &OpticsSpec) -> Result<Effects, SceneFileError> {
        let e = self.table(
            root,
            "effects",
            &[
                "distortion",
                "chromatic_aberration",
                "chromatic_scales",
                "vignetting",
                "depth_of_field",
                "lens_samples",
            ],
        )?;
        let chromatic_scales = match e.and_then(|t| t.get("chromatic_scales")) {
            Some(v) => {
                let s = self.numbers::<3>(v, "[effects] chromatic_scales")?;
                if !s.iter().all(|x| (0.5..=2.0).contains(x)) {
                    return Err(self.err(
                        "[effects] chromatic_scales",
                        "expected three radial scales R, G, B near 1 (0.5..2)",
                    ));
                }
                s
            }
            None => [1.0; 3],
        };
        let lens_samples = self
            .opt_whole(e, "effects", "lens_samples", 1..=1024)?
            .unwrap_or(10);
        let effects = Effects {
            distortion: self.bool(e, "effects", "distortion", true)?,
            chromatic_aberration: self.bool(e, "effects", "chromatic_aberration", false)?,
            chromatic_scales,
            vignetting: self.bool(e, "effects", "vignetting", false)?,
            depth_of_field: self.bool(e, "effects", "depth_of_field", false)?,
            lens_samples,
        };
        if effects.chromatic_aberration
            && matches!(optics, OpticsSpec::Camera(_))
            && e.is_none_or(|t| !t.contains_key("chromatic_scales"))
        {
            return Err(self.err(
            "[effects] chromatic_scales",
            "missing: a camera file has no glass data, so chromatic_aberration needs the per-channel radial scales, e.g. [1.002, 1.0, 0.998]",
        ));
        }
        Ok(effects)
    }

    /// `[outputs]`: at least one.
    fn outputs(&self, root: &Table) -> Result<OutputSpec, SceneFileError> {
        let o = self.table(
            root,
            "outputs",
            &[
                "color", "ids", "flow", "depth", "range", "classes", "boxes", "format",
            ],
        )?;
        let exr = match self.string(o, "outputs", "format")? {
            None | Some("png") => false,
            Some("exr") => true,
            Some(other) => {
                return Err(self.err(
                    "[outputs] format",
                    format!("expected \"png\" or \"exr\", found {other:?}"),
                ));
            }
        };
        let outputs = OutputSpec {
            color: self.bool(o, "outputs", "color", true)?,
            ids: self.bool(o, "outputs", "ids", false)?,
            flow: self.bool(o, "outputs", "flow", false)?,
            depth: self.bool(o, "outputs", "depth", false)?,
            range: self.bool(o, "outputs", "range", false)?,
            classes: self.bool(o, "outputs", "classes", false)?,
            boxes: self.bool(o, "outputs", "boxes", false)?,
            keypoints: false,
            exr,
        };
        if !(outputs.color || outputs.renders_data()) {
            return Err(self.err(
                "[outputs]",
                "every output is off: ask for color, ids, flow, depth, range, classes or boxes",
            ));
        }
        Ok(outputs)
    }

    /// `[classes]`: `"pattern" = class`, in the file's order.
    fn classes(&self, root: &Table) -> Result<Vec<crate::labels::ClassRule>, SceneFileError> {
        let Some(v) = root.get("classes") else {
            return Ok(Vec::new());
        };
        let Value::Table(t) = v else {
            return Err(self.err(
                "[classes]",
                format!(
                    "expected a table of \"name pattern\" = class ID, found {}",
                    v.type_str()
                ),
            ));
        };
        t.iter()
            .map(|(pattern, class)| {
                let key = format!("[classes] {pattern:?}");
                match class {
                    Value::Integer(c) if (0..=u16::MAX as i64).contains(c) => {
                        Ok(crate::labels::ClassRule {
                            pattern: pattern.clone(),
                            class: *c as u16,
                        })
                    }
                    other => Err(self.err(
                        &key,
                        format!(
                            "expected a class ID, a whole number 0..=65535 (classes_NNNN.png is 16-bit), found {other}"
                        ),
                    )),
                }
            })
            .collect()
    }

    /// `[[keypoints]]`: `name` and `xyz` (world metres) each.
    fn keypoints(&self, root: &Table) -> Result<Vec<crate::labels::Keypoint>, SceneFileError> {
        let Some(v) = root.get("keypoints") else {
            return Ok(Vec::new());
        };
        let Value::Array(a) = v else {
            return Err(self.err(
                "keypoints",
                "expected [[keypoints]] tables, each with name and xyz",
            ));
        };
        let mut names = std::collections::HashSet::new();
        a.iter()
            .enumerate()
            .map(|(i, k)| {
                let key = format!("[[keypoints]] {}", i + 1);
                let Value::Table(t) = k else {
                    return Err(self.err(&key, "expected a table with name and xyz"));
                };
                if let Some(other) = t.keys().find(|k| *k != "name" && *k != "xyz") {
                    return Err(
                        self.err(&format!("{key} {other}"), "unknown key; expected name, xyz")
                    );
                }
                let name = match t.get("name") {
                    Some(Value::String(s)) if !s.is_empty() => s.clone(),
                    Some(other) => {
                        return Err(self.err(
                            &format!("{key} name"),
                            format!("expected a non-empty string, found {other}"),
                        ))
                    }
                    None => return Err(self.err(&format!("{key} name"), "missing")),
                };
                if !names.insert(name.clone()) {
                    return Err(self.err(
                        &format!("{key} name"),
                        format!("{name:?} names an earlier keypoint too; give each its own"),
                    ));
                }
                let xyz = t
                    .get("xyz")
                    .ok_or_else(|| self.err(&format!("{key} xyz"), "missing (3 numbers)"))?;
                let xyz = self.numbers::<3>(xyz, &format!("{key} xyz"))?;
                Ok(crate::labels::Keypoint {
                    name,
                    xyz: DVec3::from(xyz),
                })
            })
            .collect()
    }

    /// `[accuracy] max_error_px`.
    fn accuracy(&self, root: &Table) -> Result<f64, SceneFileError> {
        let a = self.table(root, "accuracy", &["max_error_px"])?;
        let max_error_px = self
            .opt_number(a, "accuracy", "max_error_px")?
            .unwrap_or(DEFAULT_MAX_ERROR_PX);
        if !(max_error_px > 0.0) {
            return Err(self.err(
                "[accuracy] max_error_px",
                format!("expected pixels > 0, found {max_error_px}"),
            ));
        }
        Ok(max_error_px)
    }

    /// `[render]`: the background, the antialiasing and the path asked for.
    fn render(
        &self,
        root: &Table,
    ) -> Result<([f32; 4], Antialias, Option<super::PathKind>), SceneFileError> {
        let render = self.table(
            root,
            "render",
            &["background", "supersample", "jitter", "path"],
        )?;
        let path = match self.string(render, "render", "path")? {
            None => None,
            Some(name) => Some(super::PathKind::from_name(name).ok_or_else(|| {
                self.err(
                    "[render] path",
                    format!(
                        "expected one of {}, found {name:?}",
                        super::PathKind::ALL.map(|k| k.name()).join(", ")
                    ),
                )
            })?),
        };
        let background = match render.and_then(|t| t.get("background")) {
            Some(v) => self
                .numbers::<4>(v, "[render] background")?
                .map(|c| c as f32),
            None => super::DEFAULT_BACKGROUND,
        };
        let antialias = Antialias {
            supersample: self
                .opt_whole(render, "render", "supersample", 1..=super::MAX_SUPERSAMPLE)?
                .unwrap_or(1),
            jitter: self
                .opt_whole(render, "render", "jitter", 1..=super::MAX_JITTER)?
                .unwrap_or(1),
        };
        Ok((background, antialias, path))
    }

    /// `[sensor]`: the rolling shutter's readout.
    fn sensor(&self, root: &Table) -> Result<SensorSpec, SceneFileError> {
        let sensor_t = self.table(root, "sensor", &["rolling_shutter"])?;
        let sensor = SensorSpec {
            rolling_shutter: self
                .string(sensor_t, "sensor", "rolling_shutter")?
                .map(|s| {
                    s.parse::<Readout>()
                        .map_err(|e| self.err("[sensor] rolling_shutter", e.to_string()))
                })
                .transpose()?,
        };
        Ok(sensor)
    }

    /// `[[poses]]` or `[pose_sequence]`: each frame's pose, and its end pose where it has one.
    fn poses(&self, root: &Table) -> Result<(Vec<Pose>, Vec<Option<Pose>>), SceneFileError> {
        let mut poses = Vec::new();
        let mut end_poses = Vec::new();
        match root.get("poses") {
            None => {}
            Some(Value::Array(a)) => {
                for (i, v) in a.iter().enumerate() {
                    let (pose, end) = self.frame_pose(v, &format!("[[poses]] #{}", i + 1))?;
                    poses.push(pose);
                    end_poses.push(end);
                }
            }
            Some(v) => {
                return Err(self.err(
                    "poses",
                    format!("expected [[poses]] tables, found {}", v.type_str()),
                ));
            }
        }
        if let Some(seq) = self.table(root, "pose_sequence", &["from", "to", "frames"])? {
            if !poses.is_empty() {
                return Err(self.err(
                    "[pose_sequence]",
                    "give [[poses]] or [pose_sequence], not both",
                ));
            }
            let from = self.pose(
                seq.get("from")
                    .ok_or_else(|| self.err("[pose_sequence] from", "missing"))?,
                "[pose_sequence] from",
            )?;
            let to = self.pose(
                seq.get("to")
                    .ok_or_else(|| self.err("[pose_sequence] to", "missing"))?,
                "[pose_sequence] to",
            )?;
            let frames = match seq.get("frames") {
                Some(Value::Integer(n)) if (1..=100_000).contains(n) => *n as usize,
                Some(v) => {
                    return Err(self.err(
                        "[pose_sequence] frames",
                        format!("expected a whole number 1..=100000, found {v}"),
                    ));
                }
                None => return Err(self.err("[pose_sequence] frames", "missing")),
            };
            poses = interpolate(&from, &to, frames);
            end_poses = vec![None; frames];
        }
        Ok((poses, end_poses))
    }
}

/// `frames` poses from `from` to `to`: rotation by quaternion slerp, camera centre linear.
pub fn interpolate(from: &Pose, to: &Pose, frames: usize) -> Vec<Pose> {
    let qa = glam::DQuat::from_mat3(&from.rotation);
    let qb = glam::DQuat::from_mat3(&to.rotation);
    let (ca, cb) = (from.centre(), to.centre());
    (0..frames)
        .map(|k| {
            let t = if frames == 1 {
                0.0
            } else {
                k as f64 / (frames - 1) as f64
            };
            let rotation = glam::DMat3::from_quat(qa.slerp(qb, t));
            let centre = ca.lerp(cb, t);
            Pose {
                rotation,
                translation: -(rotation * centre),
            }
        })
        .collect()
}

/// A SceneFileError names its own file (and line or key): bad input.
impl From<SceneFileError> for crate::Error {
    fn from(e: SceneFileError) -> Self {
        crate::Error::Input(e.to_string())
    }
}
