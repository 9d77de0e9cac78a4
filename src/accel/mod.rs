//! Acceleration structures behind one trait: the native BVH and (feature
//! `embree`) Embree. Integrators only ever see `dyn Accel`.

pub mod brute;
pub mod bvh;
mod prims;

pub use brute::BruteForce;
pub use bvh::{Bvh, BvhStats};

use crate::geometry::Ray;
use crate::scene::{PrimHit, Scene};

/// Work done by one traversal, for the BVH-cost heat map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    pub nodes: u32,
    pub prims: u32,
}

pub trait Accel: Send + Sync {
    /// Nearest hit with `t ∈ [ray.t_min, ray.t_max]`.
    fn intersect(&self, ray: &Ray) -> Option<PrimHit>;

    /// Whether anything lies on the ray within `[t_min, t_max]` (early exit).
    fn occluded(&self, ray: &Ray) -> bool;

    /// `intersect`, counting the nodes and primitives tested. Backends that cannot
    /// count leave `stats` untouched.
    fn intersect_counted(&self, ray: &Ray, _stats: &mut TraversalStats) -> Option<PrimHit> {
        self.intersect(ray)
    }

    /// Short human-readable name, e.g. "native BVH (binned SAH)".
    fn name(&self) -> String;

    /// Bytes held by the structure.
    fn memory_bytes(&self) -> usize;
}

/// How the native BVH is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BvhBuilder {
    /// The course's split at the centroid midpoint of the longest axis.
    Midpoint,
    /// Binned surface-area heuristic.
    #[default]
    Sah,
}

/// Which backend, and its build setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelKind {
    Native(BvhBuilder),
    Embree(EmbreeQuality),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum EmbreeQuality {
    Low,
    #[default]
    Medium,
    High,
}

#[derive(Debug, thiserror::Error)]
pub enum AccelError {
    #[error("this build has no Embree backend; rebuild with --features embree")]
    EmbreeUnavailable,
    #[error("Embree: {0}")]
    Embree(String),
}

/// Builds the requested backend over `scene`.
pub fn build(scene: &Scene, kind: AccelKind) -> Result<Box<dyn Accel>, AccelError> {
    match kind {
        AccelKind::Native(b) => Ok(Box::new(bvh::Bvh::build(scene, b))),
        AccelKind::Embree(_) => Err(AccelError::EmbreeUnavailable),
    }
}
