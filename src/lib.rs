//! ember: a physically based CPU path tracer for the CS184 COLLADA scenes.
//!
//! The library holds everything; the `ember` binary only parses arguments.
//! Scene semantics follow `docs/scene-semantics.md`.

pub mod accel;
pub mod adaptive;
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
pub mod lights;
pub mod materials;
pub mod names;
pub mod output;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shard;
pub mod simd;
pub mod texture;

pub use color::Color;
pub use glam::{Vec2, Vec3};
