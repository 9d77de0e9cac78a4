//! Acceleration structures behind one trait: the native BVH and (feature
//! `embree`) Embree. Integrators only ever see `dyn Accel`.

pub mod brute;
pub mod bvh;
#[cfg(any(feature = "embree", feature = "embree4"))]
pub mod embree;
mod prims;

pub use brute::BruteForce;
pub use bvh::{Bvh, BvhStats};

use crate::geometry::Ray;
use crate::names::{display_from_table, Named};
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

    /// Shape of the tree, for backends that expose it (the native BVH).
    fn bvh_stats(&self) -> Option<BvhStats> {
        None
    }
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

impl Named for BvhBuilder {
    const WHAT: &'static str = "BVH builder";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (BvhBuilder::Sah, "sah", "Binned surface-area heuristic"),
        (
            BvhBuilder::Midpoint,
            "midpoint",
            "The course's split at the centroid midpoint of the longest axis",
        ),
    ];
}
display_from_table!(BvhBuilder);

/// Which intersection backend, without its build setting (`--accel`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Backend {
    #[default]
    Native,
    Embree,
}

impl Named for Backend {
    const WHAT: &'static str = "backend";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (Backend::Native, "native", "ember's own BVH"),
        (
            Backend::Embree,
            "embree",
            "Intel Embree (builds with --features embree only)",
        ),
    ];
}
display_from_table!(Backend);

impl Backend {
    /// Whether this build can construct the backend.
    pub fn available(self) -> bool {
        match self {
            Backend::Native => true,
            Backend::Embree => cfg!(any(feature = "embree", feature = "embree4")),
        }
    }
}

/// Which backend, and its build setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelKind {
    Native(BvhBuilder),
    Embree(EmbreeQuality),
}

impl AccelKind {
    /// `backend` with its own setting: the BVH builder or Embree's quality (the other is unused).
    pub fn new(backend: Backend, builder: BvhBuilder, quality: EmbreeQuality) -> AccelKind {
        match backend {
            Backend::Native => AccelKind::Native(builder),
            Backend::Embree => AccelKind::Embree(quality),
        }
    }

    pub fn backend(self) -> Backend {
        match self {
            AccelKind::Native(_) => Backend::Native,
            AccelKind::Embree(_) => Backend::Embree,
        }
    }
}

/// Embree's build quality (`RTC_BUILD_QUALITY_*`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum EmbreeQuality {
    Low,
    #[default]
    Medium,
    High,
}

impl Named for EmbreeQuality {
    const WHAT: &'static str = "Embree build quality";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (EmbreeQuality::Low, "low", ""),
        (EmbreeQuality::Medium, "medium", ""),
        (EmbreeQuality::High, "high", ""),
    ];
}
display_from_table!(EmbreeQuality);

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
        #[cfg(any(feature = "embree", feature = "embree4"))]
        AccelKind::Embree(q) => Ok(Box::new(embree::EmbreeAccel::build(scene, q)?)),
        #[cfg(not(any(feature = "embree", feature = "embree4")))]
        AccelKind::Embree(_) => Err(AccelError::EmbreeUnavailable),
    }
}

/// `--accel auto`: scenes with at least this many primitives go to Embree (when
/// compiled in), smaller ones to the native BVH. Measured with `ember bench accel`
/// (incoherent and shadow rays, 1 and 2 threads): the native wide BVH is ahead on
/// CBspheres_lambertian (14 primitives) and CBbunny (28.6k) and behind on the
/// displaced spheres of 249k and 998k triangles; the crossover lies between, and
/// this is its geometric middle until a finer sweep pins it down.
pub const AUTO_EMBREE_MIN_PRIMS: usize = 85_000;

/// What `--accel auto` picks for a scene, and why (for `ember info`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AutoChoice {
    pub kind: AccelKind,
    pub reason: String,
}

/// Picks the backend for `scene` from its primitive count against the measured
/// crossover [`AUTO_EMBREE_MIN_PRIMS`].
pub fn choose_auto(scene: &Scene) -> AutoChoice {
    choose_auto_for(
        scene.num_prims(),
        cfg!(any(feature = "embree", feature = "embree4")),
    )
}

fn choose_auto_for(prims: usize, embree_available: bool) -> AutoChoice {
    let native = AccelKind::Native(BvhBuilder::Sah);
    if !embree_available {
        return AutoChoice {
            kind: native,
            reason: "native BVH: this build has no Embree".into(),
        };
    }
    if prims >= AUTO_EMBREE_MIN_PRIMS {
        AutoChoice {
            kind: AccelKind::Embree(EmbreeQuality::default()),
            reason: format!(
                "Embree: {prims} primitives, at or above the measured crossover of {AUTO_EMBREE_MIN_PRIMS}"
            ),
        }
    } else {
        AutoChoice {
            kind: native,
            reason: format!(
                "native BVH (SAH): {prims} primitives, below the measured crossover of \
                 {AUTO_EMBREE_MIN_PRIMS} where Embree starts to trace faster"
            ),
        }
    }
}

/// The backends this build can use, for `ember info`.
pub fn backends_info() -> String {
    let builders: Vec<&str> = BvhBuilder::TABLE.iter().map(|r| r.1).collect();
    let native = format!("native BVH (--bvh {})", builders.join(", "));
    #[cfg(any(feature = "embree", feature = "embree4"))]
    let embree = match embree::info() {
        Ok(info) => info.to_string(),
        Err(e) => format!("Embree compiled in but unusable: {e}"),
    };
    #[cfg(not(any(feature = "embree", feature = "embree4")))]
    let embree = "Embree not compiled in (rebuild with --features embree)".to_string();
    format!("{native}; {embree}")
}

/// Sets flush-to-zero and denormals-are-zero on the calling thread, as Embree
/// recommends for tracing threads (call it from rayon's `start_handler`). Denormals
/// only arise in results below 1e-38, far beneath anything a pixel can show, while
/// their microcode assists can stall traversal. No-op off x86-64.
pub fn set_flush_denormals() {
    #[cfg(target_arch = "x86_64")]
    {
        const FTZ: u32 = 1 << 15;
        const DAZ: u32 = 1 << 6;
        let mut csr: u32 = 0;
        // SAFETY: stmxcsr/ldmxcsr exist on every x86-64 CPU and touch only `csr` and
        // MXCSR. FTZ/DAZ change only results that would be subnormal, which no caller
        // here relies on (the reason `_mm_setcsr` is deprecated is code relying on them).
        unsafe {
            std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack, preserves_flags));
            csr |= FTZ | DAZ;
            std::arch::asm!("ldmxcsr [{}]", in(reg) &csr, options(nostack, preserves_flags));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_picks_by_primitive_count() {
        let small = choose_auto_for(14, true);
        assert_eq!(small.kind, AccelKind::Native(BvhBuilder::Sah));
        assert!(small.reason.contains("14 primitives"), "{}", small.reason);
        let big = choose_auto_for(AUTO_EMBREE_MIN_PRIMS, true);
        assert_eq!(big.kind, AccelKind::Embree(EmbreeQuality::Medium));
        let without = choose_auto_for(10 * AUTO_EMBREE_MIN_PRIMS, false);
        assert_eq!(without.kind, AccelKind::Native(BvhBuilder::Sah));
    }
}
