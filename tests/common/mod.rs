//! Helpers shared by the integration tests: running the binary, rendering and noise
//! estimates, statistics (chi-square), closed forms, and COLLADA document templates.
#![allow(dead_code, unused_imports)]

pub mod analytic;
pub mod cli;
pub mod collada;
pub mod render;
pub mod stats;

pub use analytic::*;
pub use cli::*;
pub use collada::*;
pub use render::*;
pub use stats::*;
