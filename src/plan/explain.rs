//! The plan as text: what `vklens render --explain` prints and `SceneRenderer::explain`
//! returns.

use super::{Plan, Route};

impl Plan {
    /// The plan as text (what `--explain` prints), with the frame's wall time and each pass's
    /// GPU time (timestamps) where measured.
    pub fn explain(&self, measured_ms: Option<f64>, passes: &[(&str, f64)]) -> String {
        let p = self;
        let mut out = format!(
            "plan: {}\n",
            match &p.route {
                Route::Pinhole => "pinhole render".to_string(),
                Route::Vertex { tessellate } => format!(
                    "vertex path (Alg. 1){}",
                    tessellate
                        .map(|l| format!(", tessellated to {l} px"))
                        .unwrap_or_default()
                ),
                Route::Warp {
                    method,
                    chromatic,
                    map,
                } => format!(
                    "pinhole render + warp ({}{})",
                    if *map {
                        "precomputed map".to_string()
                    } else {
                        method.to_string()
                    },
                    if chromatic.is_some() {
                        ", chromatic"
                    } else {
                        ""
                    }
                ),
                Route::WarpAndVertex { method, map, .. } => {
                    let how = if *map {
                        "precomputed map".to_string()
                    } else {
                        method.to_string()
                    };
                    format!("warp ({how}, chromatic) for colour + vertex path for the data")
                }
                Route::Cube { side, chromatic } => format!(
                    "cube map of six {side}×{side} pinhole faces + sphere warp{}",
                    if chromatic.is_some() {
                        " (chromatic)"
                    } else {
                        ""
                    }
                ),
                Route::LensModel { samples, .. } => {
                    format!("image-based lens model, {samples} lens sample(s)")
                }
            }
        );
        for (i, s) in p.steps.iter().enumerate() {
            out.push_str(&format!("  {}. {}: {}\n", i + 1, s.stage.name(), s.why));
        }
        out.push_str(&format!(
            "  geometric error: {:.2e} px (budget {} px)\n",
            p.expected_error_px, p.budget_px
        ));
        if p.estimated_ms.is_finite() {
            out.push_str(&format!(
                "  estimated {:.1} ms per frame (lavapipe tables)",
                p.estimated_ms
            ));
            out.push_str(&match measured_ms {
                Some(m) => format!("; measured {m:.1} ms on frame 1\n"),
                None => "\n".into(),
            });
        } else if let Some(m) = measured_ms {
            out.push_str(&format!("  measured {m:.1} ms on frame 1\n"));
        }
        if !passes.is_empty() {
            out.push_str("  GPU time per pass (timestamps, frame 1):\n");
            for (name, ms) in passes {
                out.push_str(&format!("    {name}: {ms:.2} ms\n"));
            }
        }
        out
    }
}
