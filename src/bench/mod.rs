//! The measurements behind `vklens bench` and `benches/`: accuracy *and* time for every
//! approximation, reported as tables (and JSON lines), never asserted as wall-clock limits.

pub mod inverse;
pub mod lens;
pub mod plan;
pub mod vertex;
pub mod warp;
