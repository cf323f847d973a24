//! Lens prescriptions in the realistic-camera text format (Kolb et al. 1995, as pbrt ships
//! them): one spherical surface per line, from the object side to the image side,
//!
//! ```text
//! # radius  thickness  n_d   aperture  [abbe]
//! 29.475    3.76       1.67  25.2      47.2
//! 0         4.5        0     17.1          # radius 0 (and n 0): the aperture stop
//! ```
//!
//! all in millimetres: the curvature radius (positive: centre of curvature on the image side;
//! 0: a plane, or the stop when n is 0), the axial distance to the next surface (for the last
//! one, to the film — informative, focusing decides it), the index of refraction at the d line
//! (587.6 nm) of the medium *after* the surface (1 for air; 0 marks the stop, which is in
//! air), the clear aperture diameter, and optionally the Abbe number V_d of that medium, for
//! dispersion. `#` starts a comment.

use std::fmt;
use std::path::Path;

/// One refracting surface (or the stop).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    /// Curvature radius (mm); 0 for a plane.
    pub radius: f64,
    /// Axial distance to the next surface (mm).
    pub thickness: f64,
    /// Index of refraction (d line) of the medium after the surface.
    pub ior: f64,
    /// Clear aperture diameter (mm).
    pub aperture: f64,
    /// Abbe number V_d of the medium after the surface (None: no dispersion).
    pub abbe: Option<f64>,
    /// Whether this is the aperture stop.
    pub stop: bool,
}

/// A lens: its surfaces from object side to image side.
#[derive(Debug, Clone, PartialEq)]
pub struct Prescription {
    pub name: String,
    pub surfaces: Vec<Surface>,
}

/// A parse error: which file and line, and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct PrescriptionError {
    pub source: String,
    pub line: usize,
    pub problem: String,
}

impl fmt::Display for PrescriptionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}: {}", self.source, self.line, self.problem)
        } else {
            write!(f, "{}: {}", self.source, self.problem)
        }
    }
}

impl std::error::Error for PrescriptionError {}

/// The d, F and C lines (µm) that define n_d and V_d.
pub const LAMBDA_D: f64 = 0.587_56;
pub const LAMBDA_F: f64 = 0.486_13;
pub const LAMBDA_C: f64 = 0.656_27;

impl Surface {
    /// Index of the medium after the surface at `lambda_um`, from n_d and V_d with a two-term
    /// Cauchy law n = A + B/λ² fitted so that n(d) = n_d and n(F) − n(C) = (n_d − 1)/V_d.
    pub fn ior_at(&self, lambda_um: f64) -> f64 {
        match self.abbe {
            Some(v) if self.ior > 1.0 => {
                let b = (self.ior - 1.0) / v / (LAMBDA_F.powi(-2) - LAMBDA_C.powi(-2));
                let a = self.ior - b / (LAMBDA_D * LAMBDA_D);
                a + b / (lambda_um * lambda_um)
            }
            _ => self.ior,
        }
    }
}

impl Prescription {
    /// Parses the text of a lens file; `source` names it in errors.
    pub fn parse(text: &str, source: &str) -> Result<Self, PrescriptionError> {
        let err = |line: usize, problem: String| PrescriptionError {
            source: source.to_string(),
            line,
            problem,
        };
        let mut lines = Vec::new();
        let mut surfaces = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let content = raw.split('#').next().unwrap_or("").trim();
            if content.is_empty() {
                continue;
            }
            let fields: Vec<&str> = content.split_whitespace().collect();
            if !(4..=5).contains(&fields.len()) {
                return Err(err(
                    line,
                    format!(
                        "expected 4 or 5 numbers (radius thickness n aperture [abbe]), found {}",
                        fields.len()
                    ),
                ));
            }
            let names = [
                "radius",
                "thickness",
                "index of refraction",
                "aperture",
                "Abbe number",
            ];
            let mut v = [0.0f64; 5];
            for (k, f) in fields.iter().enumerate() {
                v[k] = f
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        err(line, format!("{} {f:?} is not a finite number", names[k]))
                    })?;
            }
            let [radius, thickness, ior, aperture, abbe] = v;
            let stop = ior == 0.0;
            if stop && radius != 0.0 {
                return Err(err(
                    line,
                    format!("the stop (n = 0) must be flat, radius is {radius}"),
                ));
            }
            if !stop && !(1.0..=4.0).contains(&ior) {
                return Err(err(
                    line,
                    format!("index of refraction {ior}: expected 1..4 (or 0 for the stop)"),
                ));
            }
            if thickness < 0.0 {
                return Err(err(line, format!("thickness {thickness} is negative")));
            }
            if aperture <= 0.0 {
                return Err(err(line, format!("aperture {aperture} must be positive")));
            }
            if radius != 0.0 && aperture > 2.0 * radius.abs() {
                return Err(err(
                    line,
                    format!("aperture {aperture} is wider than the sphere of radius {radius}"),
                ));
            }
            if fields.len() == 5 && abbe <= 0.0 {
                return Err(err(line, format!("Abbe number {abbe} must be positive")));
            }
            lines.push(line);
            surfaces.push(Surface {
                radius,
                thickness,
                ior: if stop { 1.0 } else { ior },
                aperture,
                abbe: (fields.len() == 5 && !stop).then_some(abbe),
                stop,
            });
        }
        if surfaces.len() < 2 {
            return Err(err(0, "a lens needs at least two surfaces".into()));
        }
        // Two consecutive surfaces must not cross inside their common clear aperture: glass
        // (or air) of negative thickness is no lens a ray could pass.
        let sag = |r: f64, h: f64| {
            if r == 0.0 {
                0.0
            } else {
                r - r.signum() * (r * r - h * h).max(0.0).sqrt()
            }
        };
        for i in 0..surfaces.len() - 1 {
            let (a, b) = (&surfaces[i], &surfaces[i + 1]);
            let h_max = 0.5 * a.aperture.min(b.aperture);
            for k in 0..=64 {
                let h = h_max * k as f64 / 64.0;
                let gap = a.thickness + sag(b.radius, h) - sag(a.radius, h);
                if gap < -1e-9 * (1.0 + a.thickness) {
                    return Err(err(
                        lines[i + 1],
                        format!(
                            "this surface crosses the one on line {} at {h:.3} mm from the axis (by {:.3} mm): the thickness {} there is too small for these radii and apertures",
                            lines[i],
                            -gap,
                            a.thickness
                        ),
                    ));
                }
            }
        }
        match surfaces.iter().filter(|s| s.stop).count() {
            0 | 1 => {}
            n => {
                return Err(err(
                    0,
                    format!("{n} aperture stops (radius 0, n 0); expected one"),
                ))
            }
        }
        let name = text
            .lines()
            .find_map(|l| l.trim().strip_prefix('#').map(|c| c.trim().to_string()))
            .filter(|c| !c.is_empty())
            .unwrap_or_else(|| source.to_string());
        Ok(Prescription { name, surfaces })
    }

    /// Reads a lens file.
    pub fn load(path: &Path) -> Result<Self, PrescriptionError> {
        let source = path.display().to_string();
        let text = crate::io::read_text(path).map_err(|e| PrescriptionError {
            source: source.clone(),
            line: 0,
            problem: format!("cannot read: {e}"),
        })?;
        Self::parse(&text, &source)
    }

    /// Index of the aperture stop (the first surface when none is marked).
    pub fn stop_index(&self) -> usize {
        self.surfaces.iter().position(|s| s.stop).unwrap_or(0)
    }

    /// The same lens seen from the image side: surfaces in reverse order, radii negated,
    /// each medium moved to the other side of its surface. A ray traced through it from the
    /// film, in the mirrored coordinate `z' = rear vertex z − z`, is the ray a film point
    /// sends out through the lens (Heidrich et al. Sec. 3.1 traces from the film this way).
    pub fn reversed(&self) -> Prescription {
        let n = self.surfaces.len();
        let medium_before = |i: usize| -> (f64, Option<f64>) {
            if i == 0 {
                (1.0, None)
            } else {
                (self.surfaces[i - 1].ior, self.surfaces[i - 1].abbe)
            }
        };
        let surfaces = (0..n)
            .rev()
            .map(|i| {
                let s = &self.surfaces[i];
                let (ior, abbe) = medium_before(i);
                Surface {
                    radius: -s.radius,
                    thickness: if i == 0 {
                        0.0
                    } else {
                        self.surfaces[i - 1].thickness
                    },
                    ior,
                    aperture: s.aperture,
                    abbe,
                    stop: s.stop,
                }
            })
            .collect();
        Prescription {
            name: format!("{} (reversed)", self.name),
            surfaces,
        }
    }

    /// Axial position (mm) of each surface's vertex, the first at 0, increasing towards the
    /// image.
    pub fn vertex_positions(&self) -> Vec<f64> {
        let mut z = 0.0;
        self.surfaces
            .iter()
            .map(|s| {
                let here = z;
                z += s.thickness;
                here
            })
            .collect()
    }
}

/// A PrescriptionError names its own file (and line or key): bad input.
impl From<PrescriptionError> for crate::Error {
    fn from(e: PrescriptionError) -> Self {
        crate::Error::Input(e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_line() {
        let e = Prescription::parse("10 1 1.5 5\n-10 x 1 5\n", "f.dat").unwrap_err();
        assert_eq!((e.line, e.to_string().contains("f.dat:2")), (2, true));
        let e = Prescription::parse("10 1 1.5 5\n-10 1 1 25\n", "f.dat").unwrap_err();
        assert!(e.problem.contains("wider than the sphere"), "{e}");
        let e = Prescription::parse("10 1 1.5 5\n5 1 0 3\n", "f.dat").unwrap_err();
        assert!(e.problem.contains("flat"), "{e}");
        let e = Prescription::parse("10 1 1.5\n", "f.dat").unwrap_err();
        assert!(e.problem.contains("4 or 5"), "{e}");
    }

    #[test]
    fn cauchy_dispersion_matches_abbe() {
        let s = Surface {
            radius: 10.0,
            thickness: 1.0,
            ior: 1.5168,
            aperture: 5.0,
            abbe: Some(64.17),
            stop: false,
        };
        assert!((s.ior_at(LAMBDA_D) - 1.5168).abs() < 1e-12);
        let v = (s.ior_at(LAMBDA_D) - 1.0) / (s.ior_at(LAMBDA_F) - s.ior_at(LAMBDA_C));
        assert!((v - 64.17).abs() < 1e-9);
    }
}
