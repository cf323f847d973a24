//! The cameras a file holds, whatever its format: each reader lists them ([`Listing`]: the
//! format it took the file for, and per camera its name as the file writes it and the camera or
//! why it cannot load), and one function picks the one asked for by index, name and size
//! ([`LoadOptions`]). `vklens cameras` prints the listing; every command that takes
//! `--camera` loads through [`select`].

use crate::model::Camera;
use crate::{Error, Result};

/// Which camera of a file to load, and the image size where the file has none.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// 0-based position in the file (`--camera-index`); `None` with no name: the first.
    pub index: Option<usize>,
    /// The camera's name as the file writes it (`--camera-name`): `cam1`, `M2`, `LEFT`,
    /// `right`, a COLMAP camera id.
    pub name: Option<String>,
    /// Width and height for a file that gives none (`--size WxH`); where the file gives one,
    /// it must agree.
    pub size: Option<(u32, u32)>,
}

/// One camera of a file.
#[derive(Debug)]
pub struct Found {
    /// Its name as the file writes it (empty where the format names none).
    pub name: String,
    /// The camera, or why it cannot load.
    pub camera: Result<Camera>,
}

impl Found {
    /// A camera named `name`.
    pub fn new(name: impl Into<String>, camera: Result<Camera>) -> Self {
        Found {
            name: name.into(),
            camera,
        }
    }
}

/// Every camera of a file, and the format the file was read as.
#[derive(Debug)]
pub struct Listing {
    /// The format, as a user would name it ("Kalibr camchain", "ORB-SLAM3 settings").
    pub format: &'static str,
    pub cameras: Vec<Found>,
}

impl Listing {
    /// A file of one camera.
    pub fn one(format: &'static str, name: impl Into<String>, camera: Result<Camera>) -> Self {
        Listing {
            format,
            cameras: vec![Found::new(name, camera)],
        }
    }
}

/// The image size of a camera: the file's, or the one the caller gives for a file without
/// one. Both given must agree: vklens does not rescale a calibration silently.
pub fn size_or(file: Option<(u32, u32)>, given: Option<(u32, u32)>) -> Result<(u32, u32)> {
    match (file, given) {
        (Some(f), Some(g)) if f != g => Err(Error::argument(
            "size",
            format!(
                "the file gives an image size of {}×{}, but {}×{} was asked: a calibration holds for the size it was made at",
                f.0, f.1, g.0, g.1
            ),
        )),
        (Some(s), _) | (None, Some(s)) => Ok(s),
        (None, None) => Err(Error::argument(
            "size",
            "the file gives no image size: give the size of its images",
        )),
    }
}

/// Parses `--size` / `size=` text: `WxH` (or `W×H`).
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let bad = || {
        Error::argument(
            "size",
            format!("expected WIDTHxHEIGHT in pixels (e.g. 752x480), got `{s}`"),
        )
    };
    let (w, h) = s.split_once(['x', 'X', '×']).ok_or_else(bad)?;
    let side = |t: &str| {
        t.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (1..=crate::model::MAX_IMAGE_SIDE).contains(v))
    };
    Ok((side(w).ok_or_else(bad)?, side(h).ok_or_else(bad)?))
}

/// The camera `options` ask for from a listing: by name, else by index, else the first. The
/// error names the format and, for a camera that cannot load, which camera it is.
pub fn select(listing: Listing, options: &LoadOptions) -> Result<Camera> {
    let Listing { format, cameras } = listing;
    let names = || {
        let named: Vec<String> = cameras
            .iter()
            .enumerate()
            .map(|(i, f)| {
                if f.name.is_empty() {
                    format!("{i}")
                } else {
                    format!("{i}: {}", f.name)
                }
            })
            .collect();
        named.join(", ")
    };
    let position = match (&options.name, options.index) {
        (Some(name), index) => {
            let i = cameras
                .iter()
                .position(|f| f.name == *name)
                .ok_or_else(|| {
                    Error::argument(
                        "camera_name",
                        format!(
                            "no camera named `{name}` in this {format} (it holds {})",
                            names()
                        ),
                    )
                })?;
            if let Some(index) = index.filter(|&x| x != i) {
                return Err(Error::input(format!(
                    "camera `{name}` is index {i} of this {format}, but index {index} was asked too"
                )));
            }
            i
        }
        (None, index) => {
            let i = index.unwrap_or(0);
            if i >= cameras.len() {
                return Err(Error::argument(
                    "camera_index",
                    if cameras.len() == 1 {
                        format!(
                            "camera index {i} asked, but this {format} holds one camera (index 0)"
                        )
                    } else {
                        format!(
                            "camera index {i} asked, but this {format} holds {} cameras ({})",
                            cameras.len(),
                            names()
                        )
                    },
                ));
            }
            i
        }
    };
    let several = cameras.len() > 1;
    let found = cameras
        .into_iter()
        .nth(position)
        .ok_or_else(|| Error::input(format!("this {format} holds no camera")))?;
    let size = options.size;
    found
        .camera
        .and_then(|c| {
            // A file that gives a size keeps it: a different one asked for is refused.
            size_or(Some((c.width, c.height)), size)?;
            Ok(c)
        })
        .map_err(|e| {
            let e = if several && !found.name.is_empty() {
                e.context(format!("camera `{}`", found.name))
            } else {
                e
            };
            e.context(format!("read as {}", article(format)))
        })
}

/// "a Kalibr camchain", "an OpenCV FileStorage file".
pub fn article(format: &str) -> String {
    // By sound: initialisms read letter by letter ("an NCore", "an SVO", "an LSD-SLAM").
    let first_word = format.split([' ', '/', '-']).next().unwrap_or("");
    let initialism =
        first_word.len() > 1 && first_word.chars().take(2).all(|c| c.is_ascii_uppercase());
    let vowel = if initialism {
        first_word.starts_with(['A', 'E', 'F', 'H', 'I', 'L', 'M', 'N', 'O', 'R', 'S', 'X'])
    } else {
        // "Eu" sounds like "you" (a EuRoC file).
        first_word.starts_with(['A', 'E', 'I', 'O', 'U', 'a', 'e', 'i', 'o', 'u'])
            && !first_word.starts_with("Eu")
    };
    format!("{} {format}", if vowel { "an" } else { "a" })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_agree() {
        assert_eq!(parse_size("752x480").expect("size"), (752, 480));
        assert_eq!(parse_size("640×360").expect("size"), (640, 360));
        for bad in ["", "752", "0x480", "x", "752x-1", "1e3x2"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
        assert_eq!(size_or(None, Some((4, 3))).expect("given"), (4, 3));
        assert_eq!(size_or(Some((4, 3)), None).expect("file"), (4, 3));
        assert!(size_or(Some((4, 3)), Some((8, 6))).is_err());
        let e = size_or(None, None).expect_err("none").to_string();
        assert!(e.contains("`size`"), "{e}");
    }

    #[test]
    fn articles_go_by_sound() {
        for (format, want) in [
            ("Kalibr camchain", "a Kalibr camchain"),
            ("NCore camera JSON", "an NCore camera JSON"),
            ("SVO camera file", "an SVO camera file"),
            ("LSD-SLAM/PTAM camera file", "an LSD-SLAM/PTAM camera file"),
            ("OpenCV FileStorage file", "an OpenCV FileStorage file"),
            ("ORB-SLAM3 settings file", "an ORB-SLAM3 settings file"),
            ("DSO camera.txt", "a DSO camera.txt"),
            ("COLMAP cameras.txt", "a COLMAP cameras.txt"),
            ("EuRoC sensor.yaml", "a EuRoC sensor.yaml"),
            ("vklens camera file", "a vklens camera file"),
        ] {
            assert_eq!(article(format), want);
        }
    }
}
