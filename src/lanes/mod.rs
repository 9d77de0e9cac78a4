//! The lane types that let ember trace many paths per instruction.
//!
//! Light transport is written once over a lane type `L: Lanes`, as Mitsuba 3 writes
//! `path.cpp` once over `Float`: [`One`] runs it for one path in plain `f32`, and each
//! SIMD instruction set ([`simd`]: AVX-512, AVX2, portable) runs it for sixteen paths
//! at once. Every lane operation is the IEEE operation it names, so a path's result is
//! the same bit for bit whichever lane type ran it. [`rays`] holds the sixteen-ray
//! packets the acceleration structures trace.
//!
//! Outside this folder, code uses lane values only through these types: the
//! primitive tests for sixteen rays sit with their primitives
//! (`geometry::{triangle, sphere}`), and the BVH's packet traversal and its
//! instruction-set node tests with the BVH (`accel::bvh::{packet, wide}`), each
//! beside the one-ray code it must agree with.

pub mod math;
pub mod rays;
mod real;
pub mod simd;
mod vec3;

pub use real::{LaneMask, Real, UInt};
pub use simd::{
    capped_instruction_set, dispatch, instruction_set, instruction_set_limit,
    limit_instruction_set, prefetch, widest_instruction_set, F32s, InstructionSet, LaneBits, Mask,
    Simd, SimdTask, U32s, ALL_LANES, LANES,
};
pub use vec3::{clamp, max_nonnan, V3};

/// Three lanes of vectors of an instruction set.
pub type Vec3s<S> = V3<F32s<S>>;

/// A lane type: the token that makes lane values (an instruction set's token proves
/// the CPU has it), and the number, mask and vector types of its lanes.
pub trait Lanes: Copy + Send + Sync + 'static {
    /// Paths per value: 1 or [`LANES`].
    const WIDTH: usize;
    type F: Real<M = Self::M, U = Self::U>;
    type U: UInt<M = Self::M, F = Self::F>;
    type M: LaneMask;

    fn f(self, x: f32) -> Self::F;
    fn u(self, x: u32) -> Self::U;
    /// The lanes of `bits` (bits past `WIDTH` are ignored).
    fn mask(self, bits: LaneBits) -> Self::M;
    /// Lanes from an array (elements past `WIDTH` are ignored).
    fn f_from(self, a: [f32; LANES]) -> Self::F;
    fn u_from(self, a: [u32; LANES]) -> Self::U;

    /// Every lane.
    #[inline(always)]
    fn all(self) -> LaneBits {
        if Self::WIDTH == LANES {
            ALL_LANES
        } else {
            (1 << Self::WIDTH) - 1
        }
    }
}

/// One path at a time, in plain `f32`.
#[derive(Clone, Copy, Debug, Default)]
pub struct One;

impl Lanes for One {
    const WIDTH: usize = 1;
    type F = f32;
    type U = u32;
    type M = bool;
    #[inline(always)]
    fn f(self, x: f32) -> f32 {
        x
    }
    #[inline(always)]
    fn u(self, x: u32) -> u32 {
        x
    }
    #[inline(always)]
    fn mask(self, bits: LaneBits) -> bool {
        bits & 1 != 0
    }
    #[inline(always)]
    fn f_from(self, a: [f32; LANES]) -> f32 {
        a[0]
    }
    #[inline(always)]
    fn u_from(self, a: [u32; LANES]) -> u32 {
        a[0]
    }
}

impl<S: Simd> Lanes for S {
    const WIDTH: usize = LANES;
    type F = F32s<S>;
    type U = U32s<S>;
    type M = Mask<S>;
    #[inline(always)]
    fn f(self, x: f32) -> F32s<S> {
        F32s::splat(self, x)
    }
    #[inline(always)]
    fn u(self, x: u32) -> U32s<S> {
        U32s::splat(self, x)
    }
    #[inline(always)]
    fn mask(self, bits: LaneBits) -> Mask<S> {
        Mask::from_bits(self, bits)
    }
    #[inline(always)]
    fn f_from(self, a: [f32; LANES]) -> F32s<S> {
        F32s::from_array(self, a)
    }
    #[inline(always)]
    fn u_from(self, a: [u32; LANES]) -> U32s<S> {
        U32s::from_array(self, a)
    }
}

/// The lanes of `bits`, lowest first.
#[inline(always)]
pub fn each_lane(bits: LaneBits) -> impl Iterator<Item = usize> {
    let mut rest = bits;
    std::iter::from_fn(move || {
        (rest != 0).then(|| {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            i
        })
    })
}

/// `f(i)` in each lane `i` of `like`'s kind: for what is computed lane by lane (table
/// look-ups, f64 closed forms), with the one-path function itself.
#[inline(always)]
pub fn per_lane<F: Real>(like: F, mut f: impl FnMut(usize) -> f32) -> F {
    let mut a = [0.0f32; LANES];
    for (i, v) in a.iter_mut().enumerate().take(F::WIDTH) {
        *v = f(i);
    }
    like.array_like(a)
}

/// [`per_lane`] for vectors.
#[inline(always)]
pub fn per_lane_v3<F: Real>(like: F, mut f: impl FnMut(usize) -> glam::Vec3) -> V3<F> {
    let (mut x, mut y, mut z) = ([0.0f32; LANES], [0.0f32; LANES], [0.0f32; LANES]);
    for i in 0..F::WIDTH {
        (x[i], y[i], z[i]) = f(i).into();
    }
    V3::new(like.array_like(x), like.array_like(y), like.array_like(z))
}
