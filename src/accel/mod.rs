//! Acceleration structures behind one trait: the native BVH and (feature
//! `embree`) Embree. Integrators only ever see `dyn Accel`.

pub mod brute;
pub mod bvh;
#[cfg(any(feature = "embree", feature = "embree4"))]
pub mod embree;

mod prims;

pub use crate::lanes::rays::{HitPacket, RayPacket};
use crate::lanes::LaneBits;
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

    /// `intersect` for the lanes of `rays` in `active`, into `hits` (other lanes
    /// are left as they were). Among hits at the same `t` the lowest primitive id
    /// wins (see [`packet`]). The default traces the lanes one by one.
    fn intersect_packet(&self, rays: &RayPacket, active: LaneBits, hits: &mut HitPacket) {
        for i in (0..crate::lanes::LANES).filter(|&i| active >> i & 1 != 0) {
            hits.set(i, self.intersect(&rays.ray(i)));
        }
    }

    /// The lanes of `active` whose ray is occluded. The default traces them one by one.
    fn occluded_packet(&self, rays: &RayPacket, active: LaneBits) -> LaneBits {
        (0..crate::lanes::LANES)
            .filter(|&i| active >> i & 1 != 0 && self.occluded(&rays.ray(i)))
            .fold(0, |m, i| m | 1 << i)
    }

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
    /// Per scene: [`choose_auto`].
    #[default]
    Auto,
    Native,
    Embree,
    /// No acceleration structure: [`BruteForce`].
    None,
}

impl Named for Backend {
    const WHAT: &'static str = "backend";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (
            Backend::Auto,
            "auto",
            "Per scene: the native BVH below a measured primitive count, Embree from it in builds with Embree \
             (`ember info SCENE` says which and why)",
        ),
        (Backend::Native, "native", "ember's own BVH"),
        (
            Backend::Embree,
            "embree",
            "Intel Embree, robust mode (builds with --features embree or embree4 only)",
        ),
        (
            Backend::None,
            "none",
            "No acceleration structure: every ray tests every primitive (brute force), the baseline a BVH's \
             speed-up is measured against; slow beyond a few thousand primitives (ember warns)",
        ),
    ];
}
display_from_table!(Backend);

impl Backend {
    /// Whether this build can construct the backend.
    pub fn available(self) -> bool {
        match self {
            Backend::Auto | Backend::Native | Backend::None => true,
            Backend::Embree => cfg!(any(feature = "embree", feature = "embree4")),
        }
    }
}

/// Which backend, and its build setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelKind {
    Native(BvhBuilder),
    Embree(EmbreeMode),
    /// `--accel auto`: whichever [`choose_auto`] picks for the scene, built with these
    /// settings.
    Auto {
        bvh: BvhBuilder,
        embree: EmbreeQuality,
    },
    /// `--accel none`: [`BruteForce`], every ray against every primitive.
    None,
}

impl Default for AccelKind {
    /// Auto with the native SAH builder and Embree's medium quality.
    fn default() -> Self {
        AccelKind::Auto {
            bvh: BvhBuilder::Sah,
            embree: EmbreeQuality::Medium,
        }
    }
}

impl AccelKind {
    /// Robust Embree at `quality`: what `--accel embree` builds.
    pub fn embree(quality: EmbreeQuality) -> AccelKind {
        AccelKind::Embree(EmbreeMode::robust(quality))
    }

    /// The concrete backend for `scene`, and why: `Auto` asks [`choose_auto`], the
    /// others are what they say.
    pub fn resolve(self, scene: &Scene) -> AutoChoice {
        match self {
            AccelKind::Auto { bvh, embree } => choose_auto_for(
                scene.num_prims(),
                cfg!(any(feature = "embree", feature = "embree4")).then_some(AUTO_EMBREE_MIN_PRIMS),
                bvh,
                embree,
            ),
            kind => AutoChoice {
                kind,
                reason: "requested".into(),
            },
        }
    }
}

/// A short name, e.g. "native SAH" or "Embree medium robust".
impl std::fmt::Display for AccelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AccelKind::Native(BvhBuilder::Midpoint) => write!(f, "native midpoint"),
            AccelKind::Native(BvhBuilder::Sah) => write!(f, "native SAH"),
            AccelKind::Embree(m) => write!(f, "Embree {m}"),
            AccelKind::Auto { .. } => write!(f, "auto"),
            AccelKind::None => write!(f, "none (brute force)"),
        }
    }
}

impl AccelKind {
    /// `backend` with its own setting: the BVH builder or Embree's quality (the other is unused).
    pub fn new(backend: Backend, builder: BvhBuilder, quality: EmbreeQuality) -> AccelKind {
        match backend {
            Backend::Auto => AccelKind::Auto {
                bvh: builder,
                embree: quality,
            },
            Backend::Native => AccelKind::Native(builder),
            Backend::Embree => AccelKind::embree(quality),
            Backend::None => AccelKind::None,
        }
    }

    pub fn backend(self) -> Backend {
        match self {
            AccelKind::Native(_) => Backend::Native,
            AccelKind::Embree(_) => Backend::Embree,
            AccelKind::Auto { .. } => Backend::Auto,
            AccelKind::None => Backend::None,
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

impl EmbreeQuality {
    pub const ALL: [EmbreeQuality; 3] = [
        EmbreeQuality::Low,
        EmbreeQuality::Medium,
        EmbreeQuality::High,
    ];
}

/// How Embree builds and traverses a scene, and how ember's rays reach it. The
/// default is the fastest way found that keeps every contract of [`Accel`]
/// (BENCHMARKS.md, "Embree in renders"); the other settings are there to measure
/// what each step costs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmbreeMode {
    pub quality: EmbreeQuality,
    /// `RTC_SCENE_FLAG_ROBUST`: traversal that never misses a hit on an edge or vertex
    /// shared by two triangles, at some speed. Off means no scene flags (Embree's
    /// default, "fast").
    pub robust: bool,
    pub queries: EmbreeQueries,
    pub self_hits: EmbreeSelfHits,
    pub spheres: EmbreeSpheres,
}

/// How the 16-lane calls (`intersect_packet`, `occluded_packet`) reach Embree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmbreeQueries {
    /// Every ray alone (`rtcIntersect1`, `rtcOccluded1`), as Embree's path tracer
    /// tutorial traces; a lane's answer never depends on the other lanes.
    Single,
    /// The active lanes as one `rtcIntersect16` / `rtcOccluded16` packet (ember before
    /// issue 27; Embree emulates 16 lanes on AVX2 with two packets of 8).
    Packet16,
    /// Embree 3: the active lanes as one `rtcIntersect1M` / `rtcOccluded1M` stream
    /// (Embree 4 has no streams and traces single rays).
    Stream,
    /// Single rays, but the camera rays of a call (lanes without a skip) as coherent
    /// `rtcIntersect8` packets, one per half of the lanes with two or more.
    CameraPackets,
    /// Each half of the lanes as one `rtcIntersect8` / `rtcOccluded8` packet (Embree's
    /// native width on AVX2).
    Packet8,
    /// As `Packet8`, with Embree's coherent query flag.
    Packet8Coherent,
}

impl Named for EmbreeQueries {
    const WHAT: &'static str = "Embree queries";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (
            EmbreeQueries::Single,
            "single",
            "rtcIntersect1/rtcOccluded1 per ray",
        ),
        (
            EmbreeQueries::Packet16,
            "packet16",
            "rtcIntersect16/rtcOccluded16 per call",
        ),
        (
            EmbreeQueries::Stream,
            "stream",
            "rtcIntersect1M/rtcOccluded1M per call (Embree 3)",
        ),
        (
            EmbreeQueries::CameraPackets,
            "camera8",
            "single rays, camera rays as coherent rtcIntersect8 packets",
        ),
        (
            EmbreeQueries::Packet8,
            "packet8",
            "rtcIntersect8/rtcOccluded8 per half call",
        ),
        (
            EmbreeQueries::Packet8Coherent,
            "packet8-coherent",
            "rtcIntersect8/rtcOccluded8 per half call, coherent flag",
        ),
    ];
}
display_from_table!(EmbreeQueries);

/// How a ray spawned from a surface keeps off the primitive it leaves (its
/// [`Ray::skip`](crate::geometry::Ray::skip)) under Embree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmbreeSelfHits {
    /// A filter callback on every candidate hit of every spawned ray (ember before).
    Filter,
    /// No callback on the common path: a spawned ray is traced without the filter,
    /// and again with it only when its nearest hit is the triangle it left; shadow
    /// rays keep the filter (they stop at their first hit, so it runs about once).
    /// The answers are the filter's, exactly.
    Retry,
    /// No filter at all: the origin offset by the hit point's error bound alone keeps
    /// rays off their triangle (and the sphere test off its sphere; Embree's own
    /// sphere primitive has no such protection).
    Offset,
}

impl Named for EmbreeSelfHits {
    const WHAT: &'static str = "Embree self-hit handling";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (
            EmbreeSelfHits::Filter,
            "filter",
            "filter callback on every spawned ray",
        ),
        (
            EmbreeSelfHits::Retry,
            "retry",
            "no callback; re-traced with it when the triangle left was hit; shadow rays filtered",
        ),
        (
            EmbreeSelfHits::Offset,
            "offset",
            "offset origins only, no callback",
        ),
    ];
}
display_from_table!(EmbreeSelfHits);

/// What tests a ray against a sphere under Embree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmbreeSpheres {
    /// ember's own sphere test ([`crate::geometry::sphere`]) as Embree user geometry:
    /// the same hits as the native BVH, and a ray leaving a sphere reaches only its
    /// far side by the test itself.
    Ember,
    /// Embree's own sphere primitive (`RTC_GEOMETRY_TYPE_SPHERE_POINT`).
    Embree,
}

impl Named for EmbreeSpheres {
    const WHAT: &'static str = "Embree spheres";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (
            EmbreeSpheres::Ember,
            "ember",
            "ember's sphere test as user geometry",
        ),
        (
            EmbreeSpheres::Embree,
            "embree",
            "RTC_GEOMETRY_TYPE_SPHERE_POINT",
        ),
    ];
}
display_from_table!(EmbreeSpheres);

impl Default for EmbreeMode {
    /// Robust, so no ray slips between the triangles of a watertight mesh.
    fn default() -> Self {
        EmbreeMode::robust(EmbreeQuality::default())
    }
}

impl EmbreeMode {
    /// Robust traversal at `quality`, rays driven the default way: what `--accel
    /// embree` uses.
    pub const fn robust(quality: EmbreeQuality) -> EmbreeMode {
        EmbreeMode {
            quality,
            robust: true,
            queries: EmbreeQueries::Packet8,
            self_hits: EmbreeSelfHits::Retry,
            spheres: EmbreeSpheres::Ember,
        }
    }

    /// As [`robust`](Self::robust), without `RTC_SCENE_FLAG_ROBUST`.
    pub const fn fast(quality: EmbreeQuality) -> EmbreeMode {
        let mut mode = EmbreeMode::robust(quality);
        mode.robust = false;
        mode
    }

    /// How ember drove Embree before issue 27: every 16-lane call as one
    /// `rtcIntersect16`/`rtcOccluded16` packet, the skip filter on every spawned ray,
    /// Embree's own spheres.
    pub fn before(quality: EmbreeQuality) -> EmbreeMode {
        EmbreeMode {
            queries: EmbreeQueries::Packet16,
            self_hits: EmbreeSelfHits::Filter,
            spheres: EmbreeSpheres::Embree,
            ..EmbreeMode::robust(quality)
        }
    }

    /// The scene flags this mode sets, as Embree names them.
    pub fn scene_flags(self) -> &'static str {
        if self.robust {
            "ROBUST"
        } else {
            "NONE"
        }
    }

    /// How rays reach Embree, e.g. "single rays, retry, ember spheres".
    pub fn driving(self) -> String {
        format!(
            "{} queries, {} self-hits, {} spheres",
            self.queries, self.self_hits, self.spheres
        )
    }
}

/// "medium robust" or "medium fast", followed by how rays reach Embree when that is
/// not the default ("medium robust (packet16 queries, filter self-hits, embree spheres)").
impl std::fmt::Display for EmbreeMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let flags = if self.robust { "robust" } else { "fast" };
        write!(f, "{} {flags}", self.quality)?;
        let default = EmbreeMode::robust(self.quality);
        if (self.queries, self.self_hits, self.spheres)
            != (default.queries, default.self_hits, default.spheres)
        {
            write!(f, " ({})", self.driving())?;
        }
        Ok(())
    }
}

#[derive(Debug, thiserror::Error)]
pub enum AccelError {
    #[error(
        "this build has no Embree backend; rebuild with --features embree (Embree 3) \
         or --features embree4 (Embree 4)"
    )]
    EmbreeUnavailable,
    #[error("Embree: {0}")]
    Embree(String),
}

/// Builds the requested backend over `scene` (`Auto` resolved for it), with as many
/// build threads as the current rayon pool.
pub fn build(scene: &Scene, kind: AccelKind) -> Result<Box<dyn Accel>, AccelError> {
    AccelBuilder::new(rayon::current_num_threads()).build(scene, kind)
}

/// Builds acceleration structures with a fixed number of build threads. The native
/// builders use the calling rayon pool; Embree builds on its own TBB pool, so the
/// builder keeps one device limited to the same thread count, created on the first
/// Embree build and shared by later ones (a benchmark times builds, not device start-up).
pub struct AccelBuilder {
    #[cfg_attr(not(any(feature = "embree", feature = "embree4")), allow(dead_code))]
    threads: usize,
    #[cfg(any(feature = "embree", feature = "embree4"))]
    device: std::sync::OnceLock<std::sync::Arc<embree::EmbreeDevice>>,
}

impl AccelBuilder {
    pub fn new(threads: usize) -> AccelBuilder {
        AccelBuilder {
            threads,
            #[cfg(any(feature = "embree", feature = "embree4"))]
            device: std::sync::OnceLock::new(),
        }
    }

    /// Builds `kind` over `scene`, resolving `Auto` for it.
    pub fn build(&self, scene: &Scene, kind: AccelKind) -> Result<Box<dyn Accel>, AccelError> {
        match kind.resolve(scene).kind {
            AccelKind::Native(b) => Ok(Box::new(bvh::Bvh::build(scene, b))),
            AccelKind::None => Ok(Box::new(BruteForce::new(scene))),
            #[cfg(any(feature = "embree", feature = "embree4"))]
            AccelKind::Embree(mode) => Ok(Box::new(self.build_embree(scene, mode)?)),
            #[cfg(not(any(feature = "embree", feature = "embree4")))]
            AccelKind::Embree(_) => Err(AccelError::EmbreeUnavailable),
            AccelKind::Auto { .. } => unreachable!("resolve never returns Auto"),
        }
    }

    /// The Embree device of this builder's thread count (created on first use).
    #[cfg(any(feature = "embree", feature = "embree4"))]
    pub fn embree_device(&self) -> Result<std::sync::Arc<embree::EmbreeDevice>, AccelError> {
        if let Some(d) = self.device.get() {
            return Ok(d.clone());
        }
        let d = std::sync::Arc::new(embree::EmbreeDevice::new(self.threads)?);
        Ok(self.device.get_or_init(|| d).clone())
    }

    /// An Embree scene in `mode`, as its concrete type (for packet queries).
    #[cfg(any(feature = "embree", feature = "embree4"))]
    pub fn build_embree(
        &self,
        scene: &Scene,
        mode: EmbreeMode,
    ) -> Result<embree::EmbreeAccel, AccelError> {
        embree::EmbreeAccel::build_mode(self.embree_device()?, scene, mode)
    }
}

/// A rayon pool of `threads` tracing threads (all cores when `None`) with
/// flush-to-zero set on each, as Embree recommends for tracing threads; the native
/// BVH gives the same image either way (tested). Renders and benchmarks both use it.
pub fn tracing_pool(
    threads: Option<usize>,
) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    let mut b = rayon::ThreadPoolBuilder::new().start_handler(|_| set_flush_denormals());
    if let Some(t) = threads {
        b = b.num_threads(t);
    }
    b.build()
}

/// `--accel auto`: scenes with at least this many primitives go to Embree (when
/// compiled in), smaller ones to the native BVH; `None`: the native BVH at every
/// size. It comes from `ember bench accel` runs, native and robust Embree
/// interleaved on displaced spheres of several sizes (BENCHMARKS.md, "Where
/// `--accel auto` switches"; `scripts/benchmarks` prints the measured crossover
/// beside this value). With the 16-wide native tree, native SAH traced incoherent,
/// shadow and camera rays faster than robust Embree on every mesh measured, 12k to
/// 4M triangles, at 1 and 2 threads: there is no crossover to switch at. (The
/// earlier 8-wide tree fell behind from about 10k–250k primitives; this was 85,000.)
/// scripts/test runs only the backend's own tests in the Embree builds because of
/// this `None`: with a crossover, every render test would depend on the feature.
pub const AUTO_EMBREE_MIN_PRIMS: Option<usize> = None;

/// What `--accel auto` picks for a scene, and why (for `ember info`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AutoChoice {
    /// Never `Auto`.
    pub kind: AccelKind,
    pub reason: String,
}

/// What `--accel auto` picks for `scene` with the default settings, from its
/// primitive count against the measured crossover [`AUTO_EMBREE_MIN_PRIMS`].
pub fn choose_auto(scene: &Scene) -> AutoChoice {
    AccelKind::default().resolve(scene)
}

/// `crossover`: `None` without Embree in this build, else the crossover to use.
fn choose_auto_for(
    prims: usize,
    crossover: Option<Option<usize>>,
    bvh: BvhBuilder,
    quality: EmbreeQuality,
) -> AutoChoice {
    let native = AccelKind::Native(bvh);
    let Some(crossover) = crossover else {
        return AutoChoice {
            kind: native,
            reason: "this build has no Embree".into(),
        };
    };
    match crossover {
        None => AutoChoice {
            kind: native,
            reason: format!(
                "{prims} primitives; the native BVH traced faster than robust Embree on \
                 every scene measured, so auto never switches (BENCHMARKS.md)"
            ),
        },
        Some(from) if prims >= from => AutoChoice {
            kind: AccelKind::embree(quality),
            reason: format!(
                "{prims} primitives, at or above the crossover of {from} \
                 from which Embree traced faster (BENCHMARKS.md)"
            ),
        },
        Some(from) => AutoChoice {
            kind: native,
            reason: format!(
                "{prims} primitives, below the crossover of {from} \
                 from which Embree traced faster (BENCHMARKS.md)"
            ),
        },
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
    let embree =
        "Embree not compiled in (rebuild with --features embree or --features embree4)".to_string();
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
        let (sah, med) = (BvhBuilder::Sah, EmbreeQuality::Medium);
        let at = Some(Some(85_000));
        let small = choose_auto_for(14, at, sah, med);
        assert_eq!(small.kind, AccelKind::Native(BvhBuilder::Sah));
        assert!(small.reason.contains("14 primitives"), "{}", small.reason);
        let big = choose_auto_for(85_000, at, sah, med);
        assert_eq!(big.kind, AccelKind::embree(EmbreeQuality::Medium));
        let without = choose_auto_for(850_000, None, sah, med);
        assert_eq!(without.kind, AccelKind::Native(BvhBuilder::Sah));
        let never = choose_auto_for(usize::MAX, Some(None), sah, med);
        assert_eq!(never.kind, AccelKind::Native(BvhBuilder::Sah));
        assert!(never.reason.contains("never switches"), "{}", never.reason);
    }

    #[test]
    fn auto_keeps_the_requested_builder_and_quality() {
        let at = Some(Some(85_000));
        let mid = choose_auto_for(10, at, BvhBuilder::Midpoint, EmbreeQuality::High);
        assert_eq!(mid.kind, AccelKind::Native(BvhBuilder::Midpoint));
        let high = choose_auto_for(1 << 20, at, BvhBuilder::Midpoint, EmbreeQuality::High);
        assert_eq!(high.kind, AccelKind::embree(EmbreeQuality::High));
        assert_eq!(high.kind.to_string(), "Embree high robust");
    }

    #[cfg(feature = "bench")]
    #[test]
    fn explicit_kinds_resolve_to_themselves() {
        let scene = crate::bench::meshes::displaced_sphere(200);
        let k = AccelKind::Native(BvhBuilder::Midpoint);
        assert_eq!(k.resolve(&scene).kind, k);
        assert_ne!(
            AccelKind::default().resolve(&scene).kind,
            AccelKind::default()
        );
    }
}
