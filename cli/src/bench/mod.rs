//! The measurements behind `vklens bench` and `cli/benches/`: accuracy *and* time for every
//! approximation, reported as tables (and JSON lines), never asserted as wall-clock limits.

pub mod inverse;
pub mod labels;
pub mod lens;
pub mod models;
pub mod plan;
pub mod report;
pub mod rolling_shutter;
pub mod startup;
pub mod vertex;
pub mod warp;
pub mod wide;

/// A JSON row's number `key` with `digits` decimals, "—" when absent (table cells).
pub(crate) fn fixed(row: &serde_json::Value, key: &str, digits: usize) -> String {
    row[key]
        .as_f64()
        .map(|x| format!("{x:.digits$}"))
        .unwrap_or_else(|| "—".into())
}

/// A JSON row's number `key` in scientific notation, "—" when absent.
pub(crate) fn sci(row: &serde_json::Value, key: &str) -> String {
    row[key]
        .as_f64()
        .map(|x| format!("{x:.1e}"))
        .unwrap_or_else(|| "—".into())
}
