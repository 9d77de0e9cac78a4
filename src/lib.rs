//! ember: a physically based CPU path tracer for the CS184 COLLADA scenes.
//!
//! The library holds the renderer and everything it reads and writes. The `ember`
//! binary (`src/main.rs`, `src/cli`) is its command line: it defines the flags, checks
//! and converts them into library settings, runs each subcommand through the library,
//! and reports to the terminal (warnings, progress bar, summary, Ctrl-C). Nothing in
//! the library depends on it, so the library is used and tested without it.
//! Scene semantics follow `docs/scene-semantics.md`.

pub mod accel;

#[cfg(feature = "bench")]
pub mod bench;
pub mod camera;
pub mod color;
pub mod data;
pub mod distribution;
pub mod export;
pub mod film;
pub mod geometry;
pub mod image_io;
pub mod image_metadata;
pub mod info;
pub mod integrators;
pub mod lanes;
pub mod lights;
pub mod materials;
pub mod names;
pub mod output;
pub mod render;
#[cfg(feature = "bench")]
pub mod report;
pub mod sampling;
pub mod scene;
pub mod shard;
pub mod texture;

pub use color::Color;
pub use glam::{Vec2, Vec3};
