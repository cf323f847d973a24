//! Camera files as users bring them, all read into one [`Camera`]:
//!
//! * vklens JSON: `{"width", "height", "fx", "fy", "cx", "cy", "dist_coeffs": [...]}`;
//!   unknown keys are ignored (the cases of the shared reference file load as they stand).
//! * OpenCV `FileStorage` as `calibrateCamera` samples write it — YAML (with the `%YAML:1.0`
//!   header of OpenCV 3/4 that strict YAML parsers reject, or `%YAML 1.2`), XML and JSON:
//!   `camera_matrix` and `distortion_coefficients` as `opencv-matrix`, `image_width`,
//!   `image_height`.
//! * ROS `camera_info` YAML (`plumb_bob`, `rational_polynomial`).
//!
//! * A Brown radial lens (the Durham radial-correction paper): `{"model": "brown", "width", "height", "c1", "c2"}`.
//!
//! Every format is first turned into a JSON tree, then read by one function, so every format
//! gets the same checks and the same error messages (file, field, value).

use std::path::Path;

use serde_json::{Map, Value};

use crate::model::{BrownRadial, Camera, Intrinsics, ModelError};
use crate::{Error, Result};

/// Reads a camera file (format detected from its content). A Brown lens file gives a camera
/// that remembers it ([`Camera::brown`]).
pub fn load_camera(path: &Path) -> Result<Camera> {
    let text =
        super::read_text(path).map_err(|e| Error::io(path, "cannot read camera file", &e))?;
    parse_camera(&text, &path.display().to_string())
}

/// Parses the text of a camera file; `origin` names it in errors.
pub fn parse_camera(text: &str, origin: &str) -> Result<Camera> {
    let err = |e: Error| e.context(origin);
    let trimmed = text.trim_start_matches('\u{feff}').trim_start();
    // A `.json` file is JSON even when broken: its error must say JSON, not YAML.
    let json = trimmed.starts_with('{') || origin.to_ascii_lowercase().ends_with(".json");
    let tree = if json {
        serde_json::from_str::<StrictJson>(trimmed)
            .map(|v| v.0)
            .map_err(|e| err(Error::input(format!("invalid JSON: {e}"))))?
    } else if trimmed.starts_with('<') {
        xml_to_tree(trimmed).map_err(err)?
    } else {
        yaml_to_tree(trimmed).map_err(err)?
    };
    match tree.get("model") {
        Some(Value::String(m)) if m == "brown" => {
            let brown = brown_from_tree(&tree).map_err(err)?;
            return Camera::from_brown(&brown).map_err(|e| err(Error::from(e)));
        }
        // A model vklens does not implement must not load as the standard model: a fisheye's
        // k1..k4 read as k1 k2 p1 p2 put pixels hundreds of thousands of pixels off.
        Some(Value::String(m)) if m != "opencv" => {
            return Err(err(Error::input(format!(
                "`model` is `{m}`; vklens reads `opencv` (OpenCV's standard model, the default) and `brown`"
            ))));
        }
        Some(Value::String(_)) | None => {}
        Some(other) => {
            return Err(err(Error::input(format!(
                "`model` must be a string (`opencv` or `brown`), got {other}"
            ))));
        }
    }
    camera_from_tree(&tree).map_err(err)
}

fn brown_from_tree(tree: &Value) -> Result<BrownRadial> {
    let obj = tree
        .as_object()
        .ok_or_else(|| Error::input("expected an object"))?;
    let width = dimension(obj, &["width", "image_width"])?;
    let height = dimension(obj, &["height", "image_height"])?;
    BrownRadial::new(
        width,
        height,
        number_field(obj, "c1")?,
        number_field(obj, "c2")?,
    )
    .map_err(Error::from)
}

/// Reads a camera from a parsed JSON object (any of the layouts above).
pub fn camera_from_value(value: &Value) -> Result<Camera> {
    camera_from_tree(value)
}

fn camera_from_tree(tree: &Value) -> Result<Camera> {
    let obj = tree
        .as_object()
        .ok_or_else(|| Error::input("expected an object/mapping at the top level"))?;
    let width = dimension(obj, &["width", "image_width"])?;
    let height = dimension(obj, &["height", "image_height"])?;

    let intrinsics = if obj.contains_key("fx") {
        Intrinsics {
            fx: number_field(obj, "fx")?,
            fy: number_field(obj, "fy")?,
            cx: number_field(obj, "cx")?,
            cy: number_field(obj, "cy")?,
        }
    } else {
        let (key, k) = matrix_data(obj, &["camera_matrix", "K", "k"])?
            .ok_or_else(|| Error::input("missing `fx` (or `camera_matrix`)"))?;
        if k.len() != 9 {
            return Err(Error::input(format!(
                "`{key}` must have 9 entries (3×3), got {}",
                k.len()
            )));
        }
        let expected_zero = [(1, "skew"), (3, "[1][0]"), (6, "[2][0]"), (7, "[2][1]")];
        for (i, what) in expected_zero {
            if k[i] != 0.0 {
                return Err(Error::input(format!(
                    "`{key}` entry {what} is {}; vklens supports camera matrices without skew only ([[fx,0,cx],[0,fy,cy],[0,0,1]])",
                    k[i]
                )));
            }
        }
        if k[8] != 1.0 {
            return Err(Error::input(format!(
                "`{key}` entry [2][2] must be 1, got {}",
                k[8]
            )));
        }
        Intrinsics {
            fx: k[0],
            fy: k[4],
            cx: k[2],
            cy: k[5],
        }
    };

    if let Some(model) = obj.get("distortion_model").and_then(Value::as_str) {
        if !["plumb_bob", "rational_polynomial", "opencv"].contains(&model) {
            return Err(Error::input(format!(
                "`distortion_model` is `{model}`; vklens reads `plumb_bob` and `rational_polynomial` (the OpenCV standard model)"
            )));
        }
    }
    let coeffs = if let Some(v) = obj.get("dist_coeffs") {
        number_list(v, "dist_coeffs")?
    } else {
        match matrix_data(obj, &["distortion_coefficients", "D", "d"])? {
            Some((_, d)) => d,
            None => Vec::new(),
        }
    };
    let coeffs = if coeffs.is_empty() {
        vec![0.0; 4]
    } else {
        coeffs
    };
    Camera::from_coeffs(width, height, intrinsics, &coeffs).map_err(|e| match e {
        ModelError::CoefficientCount(n) => Error::input(format!(
            "distortion coefficients: OpenCV accepts 4, 5, 8, 12 or 14 values, this file has {n}"
        )),
        other => Error::from(other),
    })
}

fn as_number(v: &Value) -> Option<f64> {
    match v {
        Value::Number(n) => n.as_f64(),
        // FileStorage writes `.Nan`/`.Inf` and YAML floats like `400.`; they arrive as text.
        Value::String(s) => parse_float(s),
        _ => None,
    }
}

fn parse_float(s: &str) -> Option<f64> {
    let t = s.trim();
    match t.to_ascii_lowercase().as_str() {
        ".nan" | "nan" => Some(f64::NAN),
        ".inf" | "+.inf" | "inf" => Some(f64::INFINITY),
        "-.inf" | "-inf" => Some(f64::NEG_INFINITY),
        _ => t.parse().ok(),
    }
}

fn number_field(obj: &Map<String, Value>, key: &str) -> Result<f64> {
    let v = obj
        .get(key)
        .ok_or_else(|| Error::input(format!("missing field `{key}`")))?;
    as_number(v).ok_or_else(|| Error::input(format!("field `{key}` must be a number, got {v}")))
}

fn dimension(obj: &Map<String, Value>, keys: &[&str]) -> Result<u32> {
    let (key, v) = keys
        .iter()
        .find_map(|k| obj.get(*k).map(|v| (*k, v)))
        .ok_or_else(|| {
            Error::input(format!(
                "missing field `{}` (image size)",
                keys.join("` or `")
            ))
        })?;
    let n = as_number(v)
        .ok_or_else(|| Error::input(format!("field `{key}` must be a number, got {v}")))?;
    if !(n.fract() == 0.0 && n >= 1.0 && n <= crate::model::MAX_IMAGE_SIDE as f64) {
        return Err(Error::input(format!(
            "field `{key}` must be a whole number of pixels in 1..={}, got {v}",
            crate::model::MAX_IMAGE_SIDE
        )));
    }
    Ok(n as u32)
}

fn number_list(v: &Value, key: &str) -> Result<Vec<f64>> {
    let arr = v
        .as_array()
        .ok_or_else(|| Error::input(format!("field `{key}` must be a list of numbers, got {v}")))?;
    arr.iter()
        .enumerate()
        .map(|(i, x)| {
            as_number(x).ok_or_else(|| {
                Error::input(format!("field `{key}`[{i}] must be a number, got {x}"))
            })
        })
        .collect()
}

/// An `opencv-matrix` (`{rows, cols, data}`) or a plain list under one of `keys`.
fn matrix_data<'a>(
    obj: &Map<String, Value>,
    keys: &[&'a str],
) -> Result<Option<(&'a str, Vec<f64>)>> {
    let Some((key, v)) = keys.iter().find_map(|k| obj.get(*k).map(|v| (*k, v))) else {
        return Ok(None);
    };
    let data = match v {
        Value::Object(m) => m
            .get("data")
            .ok_or_else(|| Error::input(format!("field `{key}` has no `data`")))?,
        other => other,
    };
    let values = number_list(data, &format!("{key}.data"))?;
    if let Value::Object(m) = v {
        if let (Some(r), Some(c)) = (
            m.get("rows").and_then(as_number),
            m.get("cols").and_then(as_number),
        ) {
            if (r * c) as usize != values.len() {
                return Err(Error::input(format!(
                    "field `{key}` says {r}×{c} but its data has {} values",
                    values.len()
                )));
            }
        }
    }
    Ok(Some((key, values)))
}

/// YAML (OpenCV FileStorage or ROS) → JSON tree. OpenCV's `%YAML:1.0` directive is not valid
/// YAML 1.1/1.2 syntax, so directive lines are dropped; `!!opencv-matrix` tags are ignored.
/// Most YAML nodes a camera file may expand to, an alias counted as the nodes it repeats. A
/// calibration file has a few hundred; nested aliases (a "billion laughs") would otherwise
/// expand a file of a few hundred bytes to billions of nodes.
pub const MAX_YAML_NODES: u64 = 100_000;

/// The number of nodes `text` expands to, counted from the parser's events without expanding
/// anything (an alias adds the size its anchor was recorded with).
fn yaml_expanded_nodes(text: &str) -> Result<u64> {
    use yaml_rust2::parser::{Event, EventReceiver, Parser};
    #[derive(Default)]
    struct Count {
        /// Open collections: nodes so far, anchor id.
        open: Vec<(u64, usize)>,
        /// Expanded size of each anchor.
        anchors: std::collections::HashMap<usize, u64>,
        total: u64,
    }
    impl Count {
        fn add(&mut self, n: u64) {
            self.total = self.total.saturating_add(n);
            if let Some(top) = self.open.last_mut() {
                top.0 = top.0.saturating_add(n);
            }
        }
    }
    impl EventReceiver for Count {
        fn on_event(&mut self, ev: Event) {
            match ev {
                Event::Scalar(_, _, anchor, _) => {
                    self.add(1);
                    if anchor > 0 {
                        self.anchors.insert(anchor, 1);
                    }
                }
                Event::SequenceStart(anchor, _) | Event::MappingStart(anchor, _) => {
                    self.total = self.total.saturating_add(1);
                    self.open.push((1, anchor));
                }
                Event::SequenceEnd | Event::MappingEnd => {
                    if let Some((n, anchor)) = self.open.pop() {
                        if anchor > 0 {
                            self.anchors.insert(anchor, n);
                        }
                        if let Some(top) = self.open.last_mut() {
                            top.0 = top.0.saturating_add(n);
                        }
                    }
                }
                Event::Alias(id) => {
                    let n = self.anchors.get(&id).copied().unwrap_or(1);
                    self.add(n);
                }
                _ => {}
            }
        }
    }
    let mut count = Count::default();
    Parser::new_from_str(text)
        .load(&mut count, true)
        .map_err(|e| Error::input(format!("invalid YAML: {e}")))?;
    Ok(count.total)
}

fn yaml_to_tree(text: &str) -> Result<Value> {
    use yaml_rust2::{Yaml, YamlLoader};
    let cleaned: String = text
        .lines()
        .filter(|l| !l.starts_with('%'))
        .collect::<Vec<_>>()
        .join("\n");
    let nodes = yaml_expanded_nodes(&cleaned)?;
    if nodes > MAX_YAML_NODES {
        return Err(Error::input(format!(
            "the YAML expands to {nodes} nodes (its aliases repeat anchors), more than a camera file's limit of {MAX_YAML_NODES}"
        )));
    }
    let docs = YamlLoader::load_from_str(&cleaned)
        .map_err(|e| Error::input(format!("invalid YAML: {e}")))?;
    let doc = docs
        .into_iter()
        .next()
        .ok_or_else(|| Error::input("empty YAML file"))?;
    fn convert(y: &Yaml) -> Value {
        match y {
            Yaml::Real(s) => Value::String(s.clone()),
            Yaml::Integer(i) => Value::from(*i),
            Yaml::String(s) => Value::String(s.clone()),
            Yaml::Boolean(b) => Value::Bool(*b),
            Yaml::Array(a) => Value::Array(a.iter().map(convert).collect()),
            Yaml::Hash(h) => Value::Object(
                h.iter()
                    .filter_map(|(k, v)| k.as_str().map(|k| (k.to_string(), convert(v))))
                    .collect(),
            ),
            _ => Value::Null,
        }
    }
    Ok(convert(&doc))
}

/// OpenCV FileStorage XML → JSON tree: `<opencv_storage>`'s children become keys; an element
/// with children becomes an object; `data` text becomes a list of numbers.
/// Deepest element nesting a camera file's XML may have: OpenCV's FileStorage nests three deep.
/// The tree is converted recursively, so a limit keeps a hostile file from overflowing the
/// stack (JSON, YAML and TOML readers stop at their own recursion limits).
pub const MAX_XML_DEPTH: usize = 64;

/// The deepest element nesting of an XML text, from its tags alone (a pre-filter: roxmltree
/// parses recursively, and a hostile file would overflow the stack before it could object).
fn xml_depth(text: &str) -> usize {
    let (mut depth, mut deepest) = (0usize, 0usize);
    let bytes = text.as_bytes();
    let mut i = 0;
    while let Some(k) = bytes[i..].iter().position(|&b| b == b'<') {
        let start = i + k;
        let end = bytes[start..]
            .iter()
            .position(|&b| b == b'>')
            .map_or(bytes.len(), |e| start + e);
        match bytes.get(start + 1) {
            Some(b'/') => depth = depth.saturating_sub(1),
            Some(b'!') | Some(b'?') => {}
            _ if end > 0 && bytes.get(end - 1) == Some(&b'/') => {}
            _ => {
                depth += 1;
                deepest = deepest.max(depth);
            }
        }
        i = end.min(bytes.len().saturating_sub(1)) + 1;
        if i >= bytes.len() {
            break;
        }
    }
    deepest
}

fn xml_to_tree(text: &str) -> Result<Value> {
    let depth = xml_depth(text);
    if depth > MAX_XML_DEPTH {
        return Err(Error::input(format!(
            "invalid XML: elements nest {depth} deep, more than a camera file's limit of {MAX_XML_DEPTH}"
        )));
    }
    let doc =
        roxmltree::Document::parse(text).map_err(|e| Error::input(format!("invalid XML: {e}")))?;
    let root = doc.root_element();
    if let Some(deep) = doc
        .descendants()
        .find(|n| n.is_element() && n.ancestors().nth(MAX_XML_DEPTH).is_some())
    {
        return Err(Error::input(format!(
            "invalid XML: <{}> is nested deeper than {MAX_XML_DEPTH} elements",
            deep.tag_name().name()
        )));
    }
    fn convert(node: roxmltree::Node) -> Value {
        let children: Vec<_> = node.children().filter(|c| c.is_element()).collect();
        if children.is_empty() {
            let text = node.text().unwrap_or("").trim();
            if node.tag_name().name() == "data" {
                return Value::Array(
                    text.split_whitespace()
                        .map(|t| Value::String(t.to_string()))
                        .collect(),
                );
            }
            return Value::String(text.trim_matches('"').to_string());
        }
        Value::Object(
            children
                .into_iter()
                .map(|c| (c.tag_name().name().to_string(), convert(c)))
                .collect(),
        )
    }
    Ok(convert(root))
}

/// JSON read like `serde_json::Value`, except that a key given twice in one object is an error
/// (`Value` keeps the last silently, so a file could say two things about one parameter).
struct StrictJson(Value);

impl<'de> serde::Deserialize<'de> for StrictJson {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        d.deserialize_any(StrictVisitor).map(StrictJson)
    }
}

struct StrictVisitor;

impl<'de> serde::de::Visitor<'de> for StrictVisitor {
    type Value = Value;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> std::result::Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> std::result::Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_u64<E>(self, v: u64) -> std::result::Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_f64<E>(self, v: f64) -> std::result::Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_str<E>(self, v: &str) -> std::result::Result<Value, E> {
        Ok(Value::String(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> std::result::Result<Value, E> {
        Ok(Value::String(v))
    }
    fn visit_unit<E>(self) -> std::result::Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> std::result::Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(
        self,
        mut seq: A,
    ) -> std::result::Result<Value, A::Error> {
        let mut out = Vec::new();
        while let Some(StrictJson(v)) = seq.next_element()? {
            out.push(v);
        }
        Ok(Value::Array(out))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(
        self,
        mut map: A,
    ) -> std::result::Result<Value, A::Error> {
        let mut out = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                return Err(serde::de::Error::custom(format!(
                    "key `{key}` appears twice in one object"
                )));
            }
            let StrictJson(v) = map.next_value()?;
            out.insert(key, v);
        }
        Ok(Value::Object(out))
    }
}
