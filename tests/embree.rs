//! The tests whose behaviour depends on the Embree backend, built as one binary in
//! builds with `embree` or `embree4` (the other integration tests, tests/suite.rs,
//! do not change with the feature, so scripts/test's Embree stages build only this).

#![cfg(any(feature = "embree", feature = "embree4"))]

mod common;

#[cfg(feature = "bench")]
mod embree_backend;
#[cfg(feature = "bench")]
mod embree_crosscheck;
mod embree_images;
mod embree_packets;
#[cfg(feature = "bench")]
mod embree_robustness;
