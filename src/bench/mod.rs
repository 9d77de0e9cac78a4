//! Benchmarks: speed against accuracy, and acceleration-structure cost.

pub mod chart;
pub mod converge;
pub mod stability;
