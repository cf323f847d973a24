//! What a training set needs beside the image, through the same lens: each object's name and
//! class, the class image, 2D boxes (visible and amodal) and the 3D box's corners, and named
//! keypoints. Pure CPU (f64), from the scene, the camera, the frame's pose and the rendered ID
//! and range images — so every route that renders IDs and range gets the same labels.
//!
//! Coordinates: points (keypoints, box corners) are OpenCV pixels, the top-left pixel's centre
//! at (0, 0), as `cv2.projectPoints` gives them. Boxes are in pixel edges, the image's top-left
//! corner at (0, 0): a box of columns 3..=7 is `x0 = 3, x1 = 8`.

use std::collections::HashMap;

use glam::{DVec2, DVec3};
use serde::Serialize;

use crate::model::rolling_shutter::{FrameMotion, Readout};
use crate::model::Camera;
use crate::scene::{Pose, Scene};

/// Relative tolerance of the occlusion test of corners and keypoints against the range image.
pub const OCCLUSION_TOLERANCE: f64 = 1e-3;

/// Whether `name` matches the shell glob `pattern`: `*` any run of characters, `?` one
/// character, `[abc]`, `[a-z]` and `[!abc]` one of (or none of) a set; anything else itself.
pub fn glob_match(pattern: &str, name: &str) -> bool {
    let p: Vec<char> = pattern.chars().collect();
    let n: Vec<char> = name.chars().collect();
    // Iterative matching with one backtrack point (the last `*`): linear for the usual
    // patterns, never exponential.
    let (mut i, mut j) = (0usize, 0usize);
    let mut star: Option<(usize, usize)> = None;
    while j < n.len() {
        if i < p.len() {
            match p[i] {
                '*' => {
                    star = Some((i, j));
                    i += 1;
                    continue;
                }
                '?' => {
                    i += 1;
                    j += 1;
                    continue;
                }
                '[' => {
                    if let Some((matched, next)) = class_match(&p, i, n[j]) {
                        if matched {
                            i = next;
                            j += 1;
                            continue;
                        }
                    } else if n[j] == '[' {
                        // An unclosed `[` is itself.
                        i += 1;
                        j += 1;
                        continue;
                    }
                }
                c if c == n[j] => {
                    i += 1;
                    j += 1;
                    continue;
                }
                _ => {}
            }
        }
        match star {
            Some((si, sj)) => {
                i = si + 1;
                j = sj + 1;
                star = Some((si, sj + 1));
            }
            None => return false,
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

/// A `[...]` set at `p[start]`: whether `c` is in it and the index past its `]`; `None` when
/// the set is not closed.
fn class_match(p: &[char], start: usize, c: char) -> Option<(bool, usize)> {
    let mut k = start + 1;
    let negate = matches!(p.get(k), Some('!') | Some('^'));
    if negate {
        k += 1;
    }
    let mut found = false;
    let mut first = true;
    while k < p.len() {
        if p[k] == ']' && !first {
            return Some((found != negate, k + 1));
        }
        first = false;
        if k + 2 < p.len() && p[k + 1] == '-' && p[k + 2] != ']' {
            found |= (p[k]..=p[k + 2]).contains(&c);
            k += 3;
        } else {
            found |= p[k] == c;
            k += 1;
        }
    }
    None
}

/// One entry of a scene file's `[classes]` table: object names matching `pattern` (a shell
/// glob) are of class `class`. The first matching entry wins; an object none matches is
/// class 0.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClassRule {
    pub pattern: String,
    pub class: u16,
}

/// The class of an object named `name`: the first rule whose pattern matches, else 0.
pub fn class_of(rules: &[ClassRule], name: &str) -> u16 {
    rules
        .iter()
        .find(|r| glob_match(&r.pattern, name))
        .map_or(0, |r| r.class)
}

/// One object of the scene as `objects.json` lists it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ObjectLabel {
    pub id: u32,
    pub name: String,
    pub class: u16,
}

/// Every object of `scene` (each ID its mesh carries) with its name and class.
pub fn object_labels(scene: &Scene, rules: &[ClassRule]) -> Vec<ObjectLabel> {
    scene
        .object_ids()
        .into_iter()
        .map(|id| {
            let name = scene.object_name(id);
            let class = class_of(rules, &name);
            ObjectLabel { id, name, class }
        })
        .collect()
}

/// The class image of an ID image: each pixel its object's class (0 for the background and
/// for an ID no object has). A lookup per pixel, so nothing is ever blended.
pub fn class_image(ids: &[u32], objects: &[ObjectLabel]) -> Vec<u32> {
    let classes: HashMap<u32, u16> = objects.iter().map(|o| (o.id, o.class)).collect();
    ids.iter()
        .map(|id| classes.get(id).copied().unwrap_or(0) as u32)
        .collect()
}

/// How a frame sees the world: the camera, its pose when the first line is read, and where the
/// camera moves during a rolling shutter's readout, the readout and the motion.
#[derive(Debug, Clone)]
pub struct View<'a> {
    pub camera: &'a Camera,
    pub pose: Pose,
    pub moving: Option<(Readout, FrameMotion)>,
}

impl<'a> View<'a> {
    /// The view of a frame read from `pose` whose last line is read at `end` in `readout`
    /// order (`None`, or `end` equal to `pose`: the camera does not move during the frame).
    pub fn new(camera: &'a Camera, pose: Pose, readout: Option<(Readout, Pose)>) -> Self {
        View {
            camera,
            pose,
            moving: readout
                .filter(|(_, end)| *end != pose)
                .map(|(r, end)| (r, FrameMotion::new(pose.into(), end.into()))),
        }
    }

    /// Where the world point `x` appears (OpenCV pixel, possibly outside the image) and its
    /// range (metres from the projection centre) when it appears there; `None` where the lens
    /// does not see it. Under a moving rolling shutter, at its own line's time (the
    /// self-consistent solution).
    pub fn see(&self, x: DVec3) -> Option<(DVec2, f64)> {
        match &self.moving {
            Some((readout, motion)) => {
                let p = motion.project(self.camera, *readout, x)?;
                let range = motion.to_camera(p.s, x).length();
                Some((p.pixel, range))
            }
            None => {
                let c = self.pose.apply(x);
                let pixel = self.camera.project(c)?;
                Some((pixel, c.length()))
            }
        }
    }

    /// Whether the OpenCV pixel `p` lies inside the image.
    fn inside(&self, p: DVec2) -> bool {
        let (w, h) = (self.camera.width as f64, self.camera.height as f64);
        p.x >= -0.5 && p.y >= -0.5 && p.x < w - 0.5 && p.y < h - 0.5
    }

    /// Whether a point seen at `p` with range `range` is visible: inside the image, and not
    /// farther than the surface the range image holds along its own ray (by
    /// [`OCCLUSION_TOLERANCE`]): interpolated bilinearly at `p` where the four pixels around
    /// it see one surface (a surface seen at a slant changes range by far more than the
    /// tolerance across half a pixel), else the nearest pixel's.
    fn visible(&self, p: DVec2, range: f64, range_image: &[f32]) -> bool {
        if !self.inside(p) {
            return false;
        }
        let (w, h) = (self.camera.width as usize, self.camera.height as usize);
        let at = |x: usize, y: usize| {
            range_image
                .get(y.min(h - 1) * w + x.min(w - 1))
                .map_or(f64::INFINITY, |&r| r as f64)
        };
        let nearest = at((p.x + 0.5) as usize, (p.y + 0.5) as usize);
        let (x0, y0) = (p.x.max(0.0).floor(), p.y.max(0.0).floor());
        let (fx, fy) = (p.x.max(0.0) - x0, p.y.max(0.0) - y0);
        let (x0, y0) = (x0 as usize, y0 as usize);
        let four = [
            at(x0, y0),
            at(x0 + 1, y0),
            at(x0, y0 + 1),
            at(x0 + 1, y0 + 1),
        ];
        let (lo, hi) = four
            .iter()
            .fold((f64::INFINITY, 0f64), |(lo, hi), &r| (lo.min(r), hi.max(r)));
        // One surface: finite and within 5 % of each other (an edge between two objects, or
        // an object and the background, differs by more).
        let seen = if hi.is_finite() && hi <= lo * 1.05 {
            let top = four[0] + (four[1] - four[0]) * fx;
            let bottom = four[2] + (four[3] - four[2]) * fx;
            top + (bottom - top) * fy
        } else {
            nearest
        };
        !(range > seen * (1.0 + OCCLUSION_TOLERANCE))
    }
}

/// A named world point to label (`[[keypoints]]` in a scene file).
#[derive(Debug, Clone, PartialEq)]
pub struct Keypoint {
    pub name: String,
    /// World position (metres).
    pub xyz: DVec3,
}

/// A keypoint as `keypoints_NNNN.json` lists it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KeypointLabel {
    pub name: String,
    /// OpenCV pixel; `null` where the lens does not see the point.
    pub pixel: Option<[f64; 2]>,
    /// Inside the image and not hidden by nearer geometry (the range image).
    pub visible: bool,
}

/// Every keypoint through `view`, tested for occlusion against `range_image`.
pub fn keypoint_labels(
    view: &View,
    keypoints: &[Keypoint],
    range_image: &[f32],
) -> Vec<KeypointLabel> {
    keypoints
        .iter()
        .map(|k| {
            let seen = view.see(k.xyz);
            KeypointLabel {
                name: k.name.clone(),
                pixel: seen.map(|(p, _)| p.to_array()),
                visible: seen.is_some_and(|(p, r)| view.visible(p, r, range_image)),
            }
        })
        .collect()
}

/// One visible object's boxes, as `boxes_NNNN.json` lists them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BoxLabel {
    pub id: u32,
    pub name: String,
    pub class: u16,
    /// Pixels of the ID image that are this object's.
    pub visible_px: u64,
    /// The tight box of those pixels, in pixel edges (x1 = last column + 1).
    pub bbox_visible: [u32; 4],
    /// The whole object's box through the lens, occlusion ignored, clipped to the image, in
    /// pixel edges; within the scene's `max_error_px` of the exact one.
    pub bbox_full: [f64; 4],
    /// The corners of the object's world axis-aligned bounding box through the lens (OpenCV
    /// pixels; `null` where the lens does not see the corner). Corner k has x from the box's
    /// high end where bit 0 of k is set, y where bit 1 is, z where bit 2 is.
    pub corners_3d: [Option<[f64; 2]>; 8],
    /// Each corner inside the image and not hidden by nearer geometry.
    pub corners_visible: [bool; 8],
}

/// The boxes of every object with at least one pixel in `ids`, in ID order.
///
/// `bbox_full` follows every edge of the object's triangles through the lens, split until the
/// curve between samples departs from its chord by at most `max_error_px` (a straight edge's
/// image bulges between its vertices, and its extreme can lie anywhere along it): the interior
/// of a triangle maps inside the image of its edges, so the edges bound the object.
pub fn box_labels(
    view: &View,
    scene: &Scene,
    objects: &[ObjectLabel],
    ids: &[u32],
    range_image: &[f32],
    max_error_px: f64,
) -> Vec<BoxLabel> {
    let w = view.camera.width as usize;
    // The tight box and pixel count of each ID in the image.
    let mut tight: HashMap<u32, ([u32; 4], u64)> = HashMap::new();
    for (i, &id) in ids.iter().enumerate() {
        if id == 0 {
            continue;
        }
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        let e = tight.entry(id).or_insert(([x, y, x + 1, y + 1], 0));
        e.0 = [
            e.0[0].min(x),
            e.0[1].min(y),
            e.0[2].max(x + 1),
            e.0[3].max(y + 1),
        ];
        e.1 += 1;
    }
    // Each object's triangles and world bounds.
    let mesh = &scene.mesh;
    let mut triangles: HashMap<u32, Vec<[DVec3; 3]>> = HashMap::new();
    for t in mesh.indices.chunks_exact(3) {
        let v = [0, 1, 2].map(|k| &mesh.vertices[t[k] as usize]);
        if tight.contains_key(&v[0].object_id) {
            triangles
                .entry(v[0].object_id)
                .or_default()
                .push(v.map(|v| v.position()));
        }
    }
    let names: HashMap<u32, &ObjectLabel> = objects.iter().map(|o| (o.id, o)).collect();
    let mut ordered: Vec<u32> = tight.keys().copied().collect();
    ordered.sort_unstable();
    ordered
        .into_iter()
        .map(|id| {
            let (bbox_visible, visible_px) = tight[&id];
            let tris = triangles.get(&id).map_or(&[][..], |t| t.as_slice());
            let mut full = Extent::default();
            for t in tris {
                for k in 0..3 {
                    trace_edge(view, t[k], t[(k + 1) % 3], max_error_px, &mut full);
                }
            }
            let (lo, hi) = tris
                .iter()
                .flatten()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                    (lo.min(p), hi.max(p))
                });
            let corners = std::array::from_fn::<_, 8, _>(|k| {
                let pick = |bit: usize, a: f64, b: f64| if k & bit != 0 { b } else { a };
                let x = DVec3::new(
                    pick(1, lo.x, hi.x),
                    pick(2, lo.y, hi.y),
                    pick(4, lo.z, hi.z),
                );
                view.see(x)
            });
            let (name, class) = names
                .get(&id)
                .map_or((scene.object_name(id), 0), |o| (o.name.clone(), o.class));
            BoxLabel {
                id,
                name,
                class,
                visible_px,
                bbox_visible,
                bbox_full: full.clipped(view.camera.width, view.camera.height, bbox_visible),
                corners_3d: corners.map(|c| c.map(|(p, _)| p.to_array())),
                corners_visible: corners
                    .map(|c| c.is_some_and(|(p, r)| view.visible(p, r, range_image))),
            }
        })
        .collect()
}

/// Which labels a frame asks for, and what they are computed from.
#[derive(Debug, Clone, Copy)]
pub struct LabelRequest<'a> {
    /// Every object with its name and class ([`object_labels`]).
    pub objects: &'a [ObjectLabel],
    /// The class image.
    pub classes: bool,
    /// The boxes.
    pub boxes: bool,
    /// The keypoints to label (none: no keypoint list).
    pub keypoints: &'a [Keypoint],
    /// The accuracy budget of `bbox_full` (output pixels).
    pub max_error_px: f64,
}

/// A frame's labels beside its images.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameLabels {
    /// Class IDs per pixel (0: background or unclassified).
    pub classes: Option<Vec<u32>>,
    pub boxes: Option<Vec<BoxLabel>>,
    pub keypoints: Option<Vec<KeypointLabel>>,
}

/// The labels `request` asks for of a frame rendered through `view`. Errors name what the
/// frame lacks (an ID or range image the labels are read from).
pub fn frame_labels(
    view: &View,
    scene: &Scene,
    rendered: &crate::imaging::Rendered,
    request: &LabelRequest,
) -> Result<FrameLabels, String> {
    let ids = || {
        rendered
            .ids
            .as_deref()
            .ok_or("classes and boxes are read from the ID image, which the frame lacks")
    };
    let range = || {
        rendered
            .range
            .as_deref()
            .ok_or("boxes and keypoints are tested for occlusion against the range image, which the frame lacks")
    };
    let mut out = FrameLabels::default();
    if request.classes {
        out.classes = Some(class_image(ids()?, request.objects));
    }
    if request.boxes {
        out.boxes = Some(box_labels(
            view,
            scene,
            request.objects,
            ids()?,
            range()?,
            request.max_error_px,
        ));
    }
    if !request.keypoints.is_empty() {
        out.keypoints = Some(keypoint_labels(view, request.keypoints, range()?));
    }
    Ok(out)
}

/// The extreme OpenCV pixel coordinates seen so far.
#[derive(Debug, Clone, Copy)]
struct Extent {
    lo: DVec2,
    hi: DVec2,
}

impl Default for Extent {
    fn default() -> Self {
        Extent {
            lo: DVec2::INFINITY,
            hi: DVec2::NEG_INFINITY,
        }
    }
}

impl Extent {
    fn add(&mut self, p: DVec2) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    /// In pixel edges, clipped to the image; the visible box where nothing was traced (an
    /// object whose edges the lens sees nowhere, yet some pixel shows).
    fn clipped(&self, width: u32, height: u32, visible: [u32; 4]) -> [f64; 4] {
        if !(self.lo.x <= self.hi.x && self.lo.y <= self.hi.y) {
            return visible.map(|v| v as f64);
        }
        let (w, h) = (width as f64, height as f64);
        [
            (self.lo.x + 0.5).clamp(0.0, w),
            (self.lo.y + 0.5).clamp(0.0, h),
            (self.hi.x + 0.5).clamp(0.0, w),
            (self.hi.y + 0.5).clamp(0.0, h),
        ]
    }
}

/// Deepest split of one edge: 2^-24 of it, far below any pixel budget of a sane scene.
const MAX_SPLIT_DEPTH: u32 = 24;

/// Adds the image of the world segment `a`–`b` to `extent`, to `max_error_px`: where the lens
/// sees only part of it, the part it sees, found by bisection to the edge of the lens's
/// domain.
fn trace_edge(view: &View, a: DVec3, b: DVec3, max_error_px: f64, extent: &mut Extent) {
    let (pa, pb) = (view.see(a).map(|s| s.0), view.see(b).map(|s| s.0));
    if let Some(p) = pa {
        extent.add(p);
    }
    if let Some(p) = pb {
        extent.add(p);
    }
    split(view, (a, pa), (b, pb), max_error_px.max(1e-6), 0, extent);
}

fn split(
    view: &View,
    (a, pa): (DVec3, Option<DVec2>),
    (b, pb): (DVec3, Option<DVec2>),
    tolerance: f64,
    depth: u32,
    extent: &mut Extent,
) {
    if depth >= MAX_SPLIT_DEPTH {
        return;
    }
    let m = 0.5 * (a + b);
    let pm = view.see(m).map(|s| s.0);
    if let Some(p) = pm {
        extent.add(p);
    }
    let go_on = match (pa, pm, pb) {
        // Seen throughout: split while the curve leaves its chord by more than the budget,
        // or the halves are long (a curve can return to its chord's midpoint).
        (Some(pa), Some(pm), Some(pb)) => {
            (pm - 0.5 * (pa + pb)).length() > tolerance || (pb - pa).length() > 64.0
        }
        // Unseen at both ends and the middle: a segment passing through the field of view
        // is still found while it is long.
        (None, None, None) => depth < 8,
        // The domain's edge lies between: bisect towards it.
        _ => true,
    };
    if go_on {
        split(view, (a, pa), (m, pm), tolerance, depth + 1, extent);
        split(view, (m, pm), (b, pb), tolerance, depth + 1, extent);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn globs_match_as_a_shell_does() {
        for (p, n, want) in [
            ("car*", "car_3", true),
            ("car*", "scar", false),
            ("*car", "scar", true),
            ("c?r", "car", true),
            ("c?r", "cr", false),
            ("box_[rg]*", "box_red", true),
            ("box_[rg]*", "box_blue", false),
            ("box_[!r]*", "box_blue", true),
            ("wall_[a-m]*", "wall_left", true),
            ("wall_[a-m]*", "wall_right", false),
            ("*", "", true),
            ("a*b*c", "axxbyyc", true),
            ("a*b*c", "axxbyy", false),
            ("[", "[", true),
            ("exact", "exact", true),
            ("exact", "exactly", false),
        ] {
            assert_eq!(glob_match(p, n), want, "{p:?} on {n:?}");
        }
    }

    #[test]
    fn the_first_matching_class_wins_and_the_rest_are_zero() {
        let rules = [
            ClassRule {
                pattern: "box_r*".into(),
                class: 7,
            },
            ClassRule {
                pattern: "box_*".into(),
                class: 2,
            },
        ];
        assert_eq!(class_of(&rules, "box_red"), 7);
        assert_eq!(class_of(&rules, "box_blue"), 2);
        assert_eq!(class_of(&rules, "floor"), 0);
        let scene = crate::scene::builtin::boxes();
        let objects = object_labels(&scene, &rules);
        let got: Vec<(u32, &str, u16)> = objects
            .iter()
            .map(|o| (o.id, o.name.as_str(), o.class))
            .collect();
        assert_eq!(
            got,
            [
                (1, "floor", 0),
                (2, "box_red", 7),
                (3, "box_green", 2),
                (4, "box_blue", 2)
            ]
        );
        assert_eq!(
            class_image(&[0, 1, 2, 3, 4, 9], &objects),
            [0, 0, 7, 2, 2, 0]
        );
    }
}
