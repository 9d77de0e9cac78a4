//! Sixteen rays traced together, one per lane (the packet path tracer's unit of
//! work). [`Accel::intersect_packet`](super::Accel::intersect_packet) finds, per
//! lane, the same nearest hit as [`Accel::intersect`](super::Accel::intersect)
//! up to ties: among hits at exactly the same `t`, the lowest primitive id wins,
//! so the answer does not depend on which rays share a packet or in what order
//! a structure visits its nodes.

use crate::geometry::triangle::TriangleRays;
use crate::geometry::{PrimHit, Ray, NO_PRIM};
use crate::lanes::{F32s, LaneBits, Lanes, Mask, Real, Simd, U32s, UInt, Vec3s, LANES, V3};

/// Sixteen rays with `t_min = 0`, structure of arrays. Lane `i` is
/// `o[·][i] + t·d[·][i]`, `t ∈ [0, t_max[i]]`, skipping primitive `skip[i]`
/// (see [`Ray::skip`]).
#[derive(Clone, Copy, Debug)]
pub struct RayPacket {
    pub o: [[f32; LANES]; 3],
    pub d: [[f32; LANES]; 3],
    pub t_max: [f32; LANES],
    pub skip: [u32; LANES],
}

impl Default for RayPacket {
    fn default() -> Self {
        RayPacket {
            o: [[0.0; LANES]; 3],
            d: [[0.0; LANES]; 3],
            t_max: [0.0; LANES],
            skip: [NO_PRIM; LANES],
        }
    }
}

impl RayPacket {
    /// Lane `i` as a ray.
    pub fn ray(&self, i: usize) -> Ray {
        Ray {
            o: glam::Vec3::new(self.o[0][i], self.o[1][i], self.o[2][i]),
            d: glam::Vec3::new(self.d[0][i], self.d[1][i], self.d[2][i]),
            t_min: 0.0,
            t_max: self.t_max[i],
            skip: self.skip[i],
        }
    }

    /// Puts `ray` (whose `t_min` must be 0) in lane `i`.
    pub fn set(&mut self, i: usize, ray: &Ray) {
        debug_assert_eq!(ray.t_min, 0.0);
        for a in 0..3 {
            self.o[a][i] = ray.o[a];
            self.d[a][i] = ray.d[a];
        }
        self.t_max[i] = ray.t_max;
        self.skip[i] = ray.skip;
    }

    /// Rays `o + t·d`, `t ≤ t_max`, skipping `skip`, in lanes `lanes`; the other
    /// lanes keep theirs.
    #[inline(always)]
    pub fn set_lanes<L: Lanes>(
        &mut self,
        l: L,
        lanes: LaneBits,
        o: V3<L::F>,
        d: V3<L::F>,
        t_max: L::F,
        skip: L::U,
    ) {
        let m = l.mask(lanes);
        self.o = V3::select(m, o, V3::from_arrays(l, &self.o)).to_arrays();
        self.d = V3::select(m, d, V3::from_arrays(l, &self.d)).to_arrays();
        self.t_max = L::F::select(m, t_max, l.f_from(self.t_max)).to_array();
        self.skip = L::U::select(m, skip, l.u_from(self.skip)).to_array();
    }
}

/// The nearest hits of a packet: lane `i` hit primitive `prim[i]` (or
/// [`NO_PRIM`]) at `t[i]` with barycentrics `b1[i]`, `b2[i]`.
#[derive(Clone, Copy, Debug)]
pub struct HitPacket {
    pub t: [f32; LANES],
    pub prim: [u32; LANES],
    pub b1: [f32; LANES],
    pub b2: [f32; LANES],
}

impl Default for HitPacket {
    fn default() -> Self {
        HitPacket {
            t: [f32::INFINITY; LANES],
            prim: [NO_PRIM; LANES],
            b1: [0.0; LANES],
            b2: [0.0; LANES],
        }
    }
}

impl HitPacket {
    pub fn hit(&self, i: usize) -> Option<PrimHit> {
        (self.prim[i] != NO_PRIM).then(|| PrimHit {
            t: self.t[i],
            prim: self.prim[i],
            b1: self.b1[i],
            b2: self.b2[i],
        })
    }

    pub fn set(&mut self, i: usize, hit: Option<PrimHit>) {
        let h = hit.unwrap_or(PrimHit {
            t: f32::INFINITY,
            prim: NO_PRIM,
            b1: 0.0,
            b2: 0.0,
        });
        (self.t[i], self.prim[i], self.b1[i], self.b2[i]) = (h.t, h.prim, h.b1, h.b2);
    }
}

/// A packet's per-ray setup in lanes, for the structures' packet traversal.
#[derive(Clone, Copy)]
pub(crate) struct PacketRays<S: Simd> {
    pub o: Vec3s<S>,
    pub d: Vec3s<S>,
    /// `1/d` per axis (glam's `recip`).
    pub inv: [F32s<S>; 3],
    /// Lanes whose direction is negative on each axis (sign bit).
    pub neg: [Mask<S>; 3],
    pub tri: TriangleRays<S>,
    pub skip: U32s<S>,
}

impl<S: Simd> PacketRays<S> {
    #[inline(always)]
    pub fn new(s: S, rays: &RayPacket) -> Self {
        let o = Vec3s::from_arrays(s, &rays.o);
        let d = Vec3s::from_arrays(s, &rays.d);
        let one = F32s::splat(s, 1.0);
        PacketRays {
            o,
            d,
            inv: [one / d.x, one / d.y, one / d.z],
            neg: [
                d.x.sign_negative(),
                d.y.sign_negative(),
                d.z.sign_negative(),
            ],
            tri: TriangleRays::new(s, o, d),
            skip: U32s::from_array(s, rays.skip),
        }
    }
}

/// The nearest hits found so far, in lanes: `t_max` shrinks as hits are found.
#[derive(Clone, Copy)]
pub(crate) struct PacketHits<S: Simd> {
    pub t_max: F32s<S>,
    pub prim: U32s<S>,
    pub b1: F32s<S>,
    pub b2: F32s<S>,
}

impl<S: Simd> PacketHits<S> {
    #[inline(always)]
    pub fn new(s: S, rays: &RayPacket) -> Self {
        PacketHits {
            t_max: F32s::from_array(s, rays.t_max),
            prim: U32s::splat(s, NO_PRIM),
            b1: F32s::splat(s, 0.0),
            b2: F32s::splat(s, 0.0),
        }
    }

    /// Takes the hits of `prim` in lanes `hit` (all with `t ≤ t_max`) that are
    /// nearer than the current ones, or as near with a lower primitive id.
    #[inline(always)]
    pub fn record(&mut self, s: S, hit: LaneBits, t: F32s<S>, prim: u32, b1: F32s<S>, b2: F32s<S>) {
        let mut take = hit & t.lt(self.t_max).bits();
        let tied = hit & t.eq(self.t_max).bits();
        if tied != 0 {
            take |= self.lower_id_lanes(tied, prim);
        }
        let m = Mask::from_bits(s, take);
        self.t_max = F32s::select(m, t, self.t_max);
        self.prim = U32s::select(m, U32s::splat(s, prim), self.prim);
        self.b1 = F32s::select(m, b1, self.b1);
        self.b2 = F32s::select(m, b2, self.b2);
    }

    /// Takes `hit` for lane `i` if it beats the lane's current hit (as `record`).
    #[inline(always)]
    pub fn record_lane(&mut self, s: S, i: usize, hit: PrimHit) {
        let (t, prim) = (self.t_max.to_array(), self.prim.to_array());
        if hit.t < t[i] || (hit.t == t[i] && hit.prim < prim[i]) {
            let m = Mask::from_bits(s, 1 << i);
            self.t_max = F32s::select(m, F32s::splat(s, hit.t), self.t_max);
            self.prim = U32s::select(m, U32s::splat(s, hit.prim), self.prim);
            self.b1 = F32s::select(m, F32s::splat(s, hit.b1), self.b1);
            self.b2 = F32s::select(m, F32s::splat(s, hit.b2), self.b2);
        }
    }

    #[cold]
    fn lower_id_lanes(&self, lanes: LaneBits, prim: u32) -> LaneBits {
        let current = self.prim.to_array();
        (0..LANES)
            .filter(|&i| lanes >> i & 1 != 0 && prim < current[i])
            .fold(0, |m, i| m | 1 << i)
    }

    /// Writes the hits of lanes `active` into `out` (a miss: `NO_PRIM`, `t = ∞`).
    #[inline(always)]
    pub fn store(&self, s: S, active: LaneBits, out: &mut HitPacket) {
        let m = Mask::from_bits(s, active);
        let missed = self.prim.eq(U32s::splat(s, NO_PRIM));
        let t = F32s::select(missed, F32s::splat(s, f32::INFINITY), self.t_max);
        out.t = F32s::select(m, t, F32s::from_array(s, out.t)).to_array();
        out.prim = U32s::select(m, self.prim, U32s::from_array(s, out.prim)).to_array();
        out.b1 = F32s::select(m, self.b1, F32s::from_array(s, out.b1)).to_array();
        out.b2 = F32s::select(m, self.b2, F32s::from_array(s, out.b2)).to_array();
    }
}
