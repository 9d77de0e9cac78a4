//! The brute-force oracle: every ray tests every primitive. It shares only the
//! primitive tests with the BVH, so comparing the two checks the BVH's builders
//! and traversal; it is also the baseline the BVH's speed-up is measured against.

use super::prims::{hittable_prims, PrimRay, PrimStore};
use super::{Accel, TraversalStats};
use crate::geometry::Ray;
use crate::scene::{PrimHit, PrimId, Scene};

pub struct BruteForce {
    prims: PrimStore,
}

impl BruteForce {
    pub fn new(scene: &Scene) -> Self {
        let order: Vec<PrimId> = hittable_prims(scene)
            .into_iter()
            .map(|(id, _)| id)
            .collect();
        BruteForce {
            prims: PrimStore::new(scene, &order),
        }
    }
}

impl Accel for BruteForce {
    fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.intersect_counted(ray, &mut TraversalStats::default())
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let r = PrimRay::new(ray);
        (0..self.prims.len()).any(|i| self.prims.intersect(i, &r, ray.t_max).is_some())
    }

    fn intersect_counted(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<PrimHit> {
        let r = PrimRay::new(ray);
        let mut best: Option<PrimHit> = None;
        let mut t_max = ray.t_max;
        for i in 0..self.prims.len() {
            if let Some(h) = self.prims.intersect(i, &r, t_max) {
                t_max = h.t;
                best = Some(h);
            }
        }
        stats.prims += self.prims.len() as u32;
        best
    }

    fn name(&self) -> String {
        "brute force".into()
    }

    fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.prims.memory_bytes()
    }
}

/// Primitive tests one thread of [`BruteForce`] makes per second: 2.1–2.2e8 measured
/// with `--accel none --shading normals -r 160 120 -t 1` on CBbunny and maxplanck (AMD
/// EPYC, AVX2, a core shared with other work), rounded up for an idle core; on a
/// slower machine renders take longer than the warning below says.
pub const TESTS_PER_SECOND_PER_THREAD: f64 = 3.0e8;

/// A render longer than this (by [`estimated_seconds`]) is warned about.
const WARN_ABOVE_SECONDS: f64 = 600.0;

/// About how long `rays` rays take against `prims` primitives on `threads` threads.
pub fn estimated_seconds(prims: usize, rays: f64, threads: usize) -> f64 {
    rays * prims as f64 / (TESTS_PER_SECOND_PER_THREAD * threads.max(1) as f64)
}

/// A warning when brute force over `prims` primitives would take more than ten
/// minutes for `rays` rays (an estimate: at most this many) on `threads` threads.
pub fn slow_warning(prims: usize, rays: f64, threads: usize) -> Option<String> {
    let s = estimated_seconds(prims, rays, threads);
    if s <= WARN_ABOVE_SECONDS {
        return None;
    }
    let time = match s {
        s if s < 3600.0 => format!("{:.0} minutes", s / 60.0),
        s if s < 48.0 * 3600.0 => format!("{:.1} hours", s / 3600.0),
        s => format!("{:.0} days", s / 86400.0),
    };
    let threads = crate::names::thread_count(threads);
    Some(format!(
        "--accel none tests every ray against all {prims} primitives: up to {rays:.2e} rays would take \
         about {time} on {threads}; use --accel native (the BVH) unless measuring the brute force"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warns_only_when_it_would_take_long() {
        assert!(slow_warning(14, 1e6, 2).is_none());
        let w = slow_warning(50_801, 480.0 * 360.0 * 64.0 * 6.0, 2).expect("hours");
        assert!(w.contains("hours") && w.contains("50801 primitives"), "{w}");
        assert!(slow_warning(1_000_000, 1e9, 1).unwrap().contains("days"));
    }
}
