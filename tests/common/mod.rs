//! Helpers shared by the integration tests: rendering and noise estimates,
//! statistics (chi-square), and COLLADA document templates.
#![allow(dead_code, unused_imports)]

pub mod cli;
pub mod collada;
pub mod render;
pub mod stats;

pub use cli::*;
pub use collada::*;
pub use render::*;
pub use stats::*;
