//! Sixteen lanes of `f32`/`u32` for code that runs one ray or one path per lane
//! (the light transport at sixteen lanes, packet BVH traversal).
//!
//! The code is written once, generic over an instruction set `S: Simd`, and
//! compiled three times: AVX-512 (one register per value), AVX2 (two) and a
//! portable version (arrays). [`dispatch`] picks the best the CPU has, detected
//! once. Every lane performs exactly the IEEE operations the code names, in the
//! order it names them (no fused multiply-add, exact division and square root),
//! so a lane's result is the same whatever the instruction set and whatever the
//! other lanes hold.
//!
//! Soundness: lane values can only be made from an instruction-set token (`S`),
//! and a token of a SIMD set only exists once the CPU has been found to have it,
//! so the intrinsics behind every operation on a value are available.

mod portable;
#[cfg(target_arch = "x86_64")]
mod x86;

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};
use std::sync::atomic::{AtomicU8, Ordering};

pub use portable::Portable;
#[cfg(target_arch = "x86_64")]
pub use x86::{Avx2, Avx512};

/// Lanes per value. Sixteen on AVX2 too (two registers a value, and a quarter of the
/// path kernel's instructions move registers to and from the stack), measured against
/// eight (one register a value): whole renders, 8 ÷ 16 lanes, medians of alternating
/// pairs (AMD EPYC Zen 3, 2 threads, 480×360, 64 spp): CBbunny -m 5 1.005, banana -m 3
/// 1.005, CBspheres_lambertian -m 5 1.097. Images are the same at any width.
pub const LANES: usize = 16;

/// A lane mask as bits: bit `i` is lane `i`.
pub type LaneBits = u32;

/// All sixteen lanes.
pub const ALL_LANES: LaneBits = (1 << LANES) - 1;

/// An instruction set's lane operations. Implementors are zero-sized tokens that
/// exist only where the instruction set does.
///
/// # Safety
/// An implementor's token may only be constructed after checking that the CPU
/// supports its instructions. Every function assumes the CPU has them (the lane
/// types call them only after a token was made).
#[allow(clippy::missing_safety_doc)]
pub unsafe trait Simd: Copy + Send + Sync + 'static {
    /// Whether AVX2 code (e.g. the single-ray BVH box test) may run here.
    const AVX2: bool;
    /// Whether AVX-512 code (the one-pass single-ray box test of 16-wide nodes) may run.
    const AVX512: bool;

    type F: Copy;
    type U: Copy;
    type M: Copy;
    /// Sixteen `u64`s.
    type W: Copy;

    unsafe fn f_splat(x: f32) -> Self::F;
    unsafe fn f_load(a: &[f32; LANES]) -> Self::F;
    unsafe fn f_store(v: Self::F, a: &mut [f32; LANES]);
    unsafe fn f_add(a: Self::F, b: Self::F) -> Self::F;
    unsafe fn f_sub(a: Self::F, b: Self::F) -> Self::F;
    unsafe fn f_mul(a: Self::F, b: Self::F) -> Self::F;
    unsafe fn f_div(a: Self::F, b: Self::F) -> Self::F;
    unsafe fn f_sqrt(a: Self::F) -> Self::F;
    /// `if a < b { a } else { b }` per lane: `b` when either is NaN (x86's `min`).
    unsafe fn f_min(a: Self::F, b: Self::F) -> Self::F;
    /// `if a > b { a } else { b }` per lane: `b` when either is NaN (x86's `max`).
    unsafe fn f_max(a: Self::F, b: Self::F) -> Self::F;
    unsafe fn f_lt(a: Self::F, b: Self::F) -> Self::M;
    unsafe fn f_le(a: Self::F, b: Self::F) -> Self::M;
    unsafe fn f_eq(a: Self::F, b: Self::F) -> Self::M;
    /// `a` where `m` is set, else `b`.
    unsafe fn f_select(m: Self::M, a: Self::F, b: Self::F) -> Self::F;
    /// The smallest of the lanes in `m` (`+∞` when `m` is empty; NaN lanes are
    /// ignored unless all are NaN).
    unsafe fn f_reduce_min(a: Self::F, m: Self::M) -> f32;
    unsafe fn f_to_bits(a: Self::F) -> Self::U;
    unsafe fn f_from_bits(a: Self::U) -> Self::F;
    /// Exact for values below 2²⁴ (as `u as f32`).
    unsafe fn u_to_f(a: Self::U) -> Self::F;

    unsafe fn u_splat(x: u32) -> Self::U;
    unsafe fn u_load(a: &[u32; LANES]) -> Self::U;
    unsafe fn u_store(v: Self::U, a: &mut [u32; LANES]);
    unsafe fn u_add(a: Self::U, b: Self::U) -> Self::U;
    unsafe fn u_and(a: Self::U, b: Self::U) -> Self::U;
    unsafe fn u_or(a: Self::U, b: Self::U) -> Self::U;
    unsafe fn u_xor(a: Self::U, b: Self::U) -> Self::U;
    unsafe fn u_eq(a: Self::U, b: Self::U) -> Self::M;
    unsafe fn u_select(m: Self::M, a: Self::U, b: Self::U) -> Self::U;

    /// Wrapping product (the low 32 bits).
    unsafe fn u_mul(a: Self::U, b: Self::U) -> Self::U;
    /// `a >> N` (logical) per lane.
    unsafe fn u_shr<const N: u32>(a: Self::U) -> Self::U;
    /// `a << N` per lane.
    unsafe fn u_shl<const N: u32>(a: Self::U) -> Self::U;
    /// `a.rotate_right(r)` per lane (`r < 32`).
    unsafe fn u_rotr(a: Self::U, r: Self::U) -> Self::U;
    /// `u32::reverse_bits` per lane.
    unsafe fn u_reverse_bits(a: Self::U) -> Self::U;
    /// `table[a]` per lane (every lane of `a` below 16).
    unsafe fn u_lookup16(table: &[u32; 16], a: Self::U) -> Self::U;

    unsafe fn w_splat(x: u64) -> Self::W;
    unsafe fn w_load(a: &[u64; LANES]) -> Self::W;
    unsafe fn w_store(v: Self::W, a: &mut [u64; LANES]);
    unsafe fn w_add(a: Self::W, b: Self::W) -> Self::W;
    /// Wrapping product (the low 64 bits).
    unsafe fn w_mul(a: Self::W, b: Self::W) -> Self::W;
    unsafe fn w_xor(a: Self::W, b: Self::W) -> Self::W;
    unsafe fn w_or(a: Self::W, b: Self::W) -> Self::W;
    unsafe fn w_shr<const N: u32>(a: Self::W) -> Self::W;
    unsafe fn w_shl<const N: u32>(a: Self::W) -> Self::W;
    /// The low 32 bits of each lane.
    unsafe fn w_low(a: Self::W) -> Self::U;
    unsafe fn w_select(m: Self::M, a: Self::W, b: Self::W) -> Self::W;

    unsafe fn m_and(a: Self::M, b: Self::M) -> Self::M;
    unsafe fn m_or(a: Self::M, b: Self::M) -> Self::M;
    unsafe fn m_not(a: Self::M) -> Self::M;
    unsafe fn m_bits(a: Self::M) -> LaneBits;
    unsafe fn m_from_bits(bits: LaneBits) -> Self::M;
}

/// Sixteen `f32`s.
#[derive(Clone, Copy)]
pub struct F32s<S: Simd>(S::F);
/// Sixteen `u32`s.
#[derive(Clone, Copy)]
pub struct U32s<S: Simd>(S::U);
/// Sixteen `u64`s.
#[derive(Clone, Copy)]
pub struct U64s<S: Simd>(S::W);
/// A mask of sixteen lanes.
#[derive(Clone, Copy)]
pub struct Mask<S: Simd>(S::M);

// SAFETY (all impls below): a lane value exists only if a token `S` was made,
// which proves the CPU has `S`'s instructions (see `Simd`).

impl<S: Simd> F32s<S> {
    #[inline(always)]
    pub fn splat(_: S, x: f32) -> Self {
        F32s(unsafe { S::f_splat(x) })
    }
    #[inline(always)]
    pub fn from_array(_: S, a: [f32; LANES]) -> Self {
        F32s(unsafe { S::f_load(&a) })
    }
    /// `x` in every lane (the value `self` proves the instruction set).
    #[inline(always)]
    pub fn splat_like(self, x: f32) -> Self {
        F32s(unsafe { S::f_splat(x) })
    }
    /// Lanes from an array (the value `self` proves the instruction set).
    #[inline(always)]
    pub fn from_array_like(self, a: [f32; LANES]) -> Self {
        F32s(unsafe { S::f_load(&a) })
    }
    #[inline(always)]
    pub fn to_array(self) -> [f32; LANES] {
        let mut a = [0.0; LANES];
        unsafe { S::f_store(self.0, &mut a) };
        a
    }
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        F32s(unsafe { S::f_sqrt(self.0) })
    }
    /// x86 `min`: `other` when either is NaN.
    #[inline(always)]
    pub fn min(self, other: Self) -> Self {
        F32s(unsafe { S::f_min(self.0, other.0) })
    }
    /// x86 `max`: `other` when either is NaN.
    #[inline(always)]
    pub fn max(self, other: Self) -> Self {
        F32s(unsafe { S::f_max(self.0, other.0) })
    }
    #[inline(always)]
    pub fn abs(self) -> Self {
        let bits = unsafe { S::u_and(S::f_to_bits(self.0), S::u_splat(0x7fff_ffff)) };
        F32s(unsafe { S::f_from_bits(bits) })
    }
    /// `self.copysign(sign)` per lane.
    #[inline(always)]
    pub fn copysign(self, sign: Self) -> Self {
        unsafe {
            let mag = S::u_and(S::f_to_bits(self.0), S::u_splat(0x7fff_ffff));
            let sgn = S::u_and(S::f_to_bits(sign.0), S::u_splat(0x8000_0000));
            F32s(S::f_from_bits(S::u_or(mag, sgn)))
        }
    }
    /// Lanes whose sign bit is set (so `−0` counts as negative).
    #[inline(always)]
    pub fn sign_negative(self) -> Mask<S> {
        unsafe {
            let sgn = S::u_and(S::f_to_bits(self.0), S::u_splat(0x8000_0000));
            Mask(S::u_eq(sgn, S::u_splat(0x8000_0000)))
        }
    }
    #[inline(always)]
    pub fn lt(self, o: Self) -> Mask<S> {
        Mask(unsafe { S::f_lt(self.0, o.0) })
    }
    #[inline(always)]
    pub fn le(self, o: Self) -> Mask<S> {
        Mask(unsafe { S::f_le(self.0, o.0) })
    }
    #[inline(always)]
    pub fn gt(self, o: Self) -> Mask<S> {
        o.lt(self)
    }
    #[inline(always)]
    pub fn ge(self, o: Self) -> Mask<S> {
        o.le(self)
    }
    #[inline(always)]
    pub fn eq(self, o: Self) -> Mask<S> {
        Mask(unsafe { S::f_eq(self.0, o.0) })
    }
    /// Lanes that are neither NaN nor infinite.
    #[inline(always)]
    pub fn is_finite(self) -> Mask<S> {
        let inf = F32s(unsafe { S::f_splat(f32::INFINITY) });
        self.abs().lt(inf)
    }
    #[inline(always)]
    pub fn bits(self) -> U32s<S> {
        U32s(unsafe { S::f_to_bits(self.0) })
    }
    /// `a` where `m`, else `b`.
    #[inline(always)]
    pub fn select(m: Mask<S>, a: Self, b: Self) -> Self {
        F32s(unsafe { S::f_select(m.0, a.0, b.0) })
    }
    #[inline(always)]
    pub fn lane(self, i: usize) -> f32 {
        self.to_array()[i]
    }
    /// The smallest lane of `m` (`+∞` for none).
    #[inline(always)]
    pub fn reduce_min(self, m: Mask<S>) -> f32 {
        unsafe { S::f_reduce_min(self.0, m.0) }
    }
}

impl<S: Simd> U32s<S> {
    #[inline(always)]
    pub fn splat(_: S, x: u32) -> Self {
        U32s(unsafe { S::u_splat(x) })
    }
    #[inline(always)]
    pub fn from_array(_: S, a: [u32; LANES]) -> Self {
        U32s(unsafe { S::u_load(&a) })
    }
    /// `x` in every lane (the value `self` proves the instruction set).
    #[inline(always)]
    pub fn splat_like(self, x: u32) -> Self {
        U32s(unsafe { S::u_splat(x) })
    }
    /// Lanes from an array (the value `self` proves the instruction set).
    #[inline(always)]
    pub fn from_array_like(self, a: [u32; LANES]) -> Self {
        U32s(unsafe { S::u_load(&a) })
    }
    #[inline(always)]
    pub fn to_array(self) -> [u32; LANES] {
        let mut a = [0; LANES];
        unsafe { S::u_store(self.0, &mut a) };
        a
    }
    #[inline(always)]
    pub fn eq(self, o: Self) -> Mask<S> {
        Mask(unsafe { S::u_eq(self.0, o.0) })
    }
    #[inline(always)]
    pub fn select(m: Mask<S>, a: Self, b: Self) -> Self {
        U32s(unsafe { S::u_select(m.0, a.0, b.0) })
    }
    /// Exact below 2²⁴.
    #[inline(always)]
    pub fn to_f32(self) -> F32s<S> {
        F32s(unsafe { S::u_to_f(self.0) })
    }
    #[inline(always)]
    pub fn as_f32_bits(self) -> F32s<S> {
        F32s(unsafe { S::f_from_bits(self.0) })
    }
    #[inline(always)]
    pub fn xor(self, o: Self) -> Self {
        U32s(unsafe { S::u_xor(self.0, o.0) })
    }
    #[inline(always)]
    pub fn shr<const N: u32>(self) -> Self {
        U32s(unsafe { S::u_shr::<N>(self.0) })
    }
    #[inline(always)]
    pub fn shl<const N: u32>(self) -> Self {
        U32s(unsafe { S::u_shl::<N>(self.0) })
    }
    #[inline(always)]
    pub fn wrapping_add(self, o: Self) -> Self {
        U32s(unsafe { S::u_add(self.0, o.0) })
    }
    #[inline(always)]
    pub fn wrapping_mul(self, o: Self) -> Self {
        U32s(unsafe { S::u_mul(self.0, o.0) })
    }
    #[inline(always)]
    pub fn and(self, o: Self) -> Self {
        U32s(unsafe { S::u_and(self.0, o.0) })
    }
    #[inline(always)]
    pub fn or(self, o: Self) -> Self {
        U32s(unsafe { S::u_or(self.0, o.0) })
    }
    /// `u32::reverse_bits` per lane.
    #[inline(always)]
    pub fn reverse_bits(self) -> Self {
        U32s(unsafe { S::u_reverse_bits(self.0) })
    }
    /// `table[self]` per lane (every lane below 16): a table held in registers.
    #[inline(always)]
    pub fn lookup16(self, table: &[u32; 16]) -> Self {
        U32s(unsafe { S::u_lookup16(table, self.0) })
    }
    #[inline(always)]
    pub fn rotate_right(self, r: Self) -> Self {
        U32s(unsafe { S::u_rotr(self.0, r.0) })
    }
}

impl<S: Simd> U64s<S> {
    #[inline(always)]
    pub fn splat(_: S, x: u64) -> Self {
        U64s(unsafe { S::w_splat(x) })
    }
    #[inline(always)]
    pub fn from_array(_: S, a: [u64; LANES]) -> Self {
        U64s(unsafe { S::w_load(&a) })
    }
    #[inline(always)]
    pub fn to_array(self) -> [u64; LANES] {
        let mut a = [0; LANES];
        unsafe { S::w_store(self.0, &mut a) };
        a
    }
    #[inline(always)]
    pub fn wrapping_add(self, o: Self) -> Self {
        U64s(unsafe { S::w_add(self.0, o.0) })
    }
    #[inline(always)]
    pub fn wrapping_mul(self, o: Self) -> Self {
        U64s(unsafe { S::w_mul(self.0, o.0) })
    }
    #[inline(always)]
    pub fn xor(self, o: Self) -> Self {
        U64s(unsafe { S::w_xor(self.0, o.0) })
    }
    #[inline(always)]
    pub fn or(self, o: Self) -> Self {
        U64s(unsafe { S::w_or(self.0, o.0) })
    }
    #[inline(always)]
    pub fn shr<const N: u32>(self) -> Self {
        U64s(unsafe { S::w_shr::<N>(self.0) })
    }
    #[inline(always)]
    pub fn shl<const N: u32>(self) -> Self {
        U64s(unsafe { S::w_shl::<N>(self.0) })
    }
    /// `x as u32` per lane.
    #[inline(always)]
    pub fn low32(self) -> U32s<S> {
        U32s(unsafe { S::w_low(self.0) })
    }
    #[inline(always)]
    pub fn select(m: Mask<S>, a: Self, b: Self) -> Self {
        U64s(unsafe { S::w_select(m.0, a.0, b.0) })
    }
}

impl<S: Simd> Mask<S> {
    #[inline(always)]
    pub fn from_bits(_: S, bits: LaneBits) -> Self {
        Mask(unsafe { S::m_from_bits(bits) })
    }
    #[inline(always)]
    pub fn bits(self) -> LaneBits {
        unsafe { S::m_bits(self.0) }
    }
    /// The lanes of `bits` (the value `self` proves the instruction set).
    #[inline(always)]
    pub fn from_bits_like(self, bits: LaneBits) -> Self {
        Mask(unsafe { S::m_from_bits(bits) })
    }
    #[inline(always)]
    pub fn any(self) -> bool {
        self.bits() != 0
    }
    #[inline(always)]
    pub fn and_not(self, o: Self) -> Self {
        self & !o
    }
}

macro_rules! binop {
    ($ty:ident, $tr:ident, $m:ident, $f:ident) => {
        impl<S: Simd> $tr for $ty<S> {
            type Output = Self;
            #[inline(always)]
            fn $m(self, o: Self) -> Self {
                $ty(unsafe { S::$f(self.0, o.0) })
            }
        }
    };
}
binop!(F32s, Add, add, f_add);
binop!(F32s, Sub, sub, f_sub);
binop!(F32s, Mul, mul, f_mul);
binop!(F32s, Div, div, f_div);
binop!(U32s, Add, add, u_add);
binop!(U32s, BitAnd, bitand, u_and);
binop!(U32s, BitOr, bitor, u_or);
binop!(Mask, BitAnd, bitand, m_and);
binop!(Mask, BitOr, bitor, m_or);

impl<S: Simd> Neg for F32s<S> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        let bits = unsafe { S::u_xor(S::f_to_bits(self.0), S::u_splat(0x8000_0000)) };
        F32s(unsafe { S::f_from_bits(bits) })
    }
}

impl<S: Simd> Not for Mask<S> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Mask(unsafe { S::m_not(self.0) })
    }
}

/// Asks the cache for the line holding `*p` (a hint: never faults, does nothing
/// off x86-64). Lanes that look up scene data for their hits issue these first,
/// so the misses of sixteen lanes overlap.
#[inline(always)]
pub fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults, whatever the address.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p.cast())
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Code to run with the best instruction set: `run::<S>(token)` is compiled for
/// each set, with that set's features enabled for the whole of it.
pub trait SimdTask {
    type Output;
    fn run<S: Simd>(self, s: S) -> Self::Output;
}

/// The instruction sets [`dispatch`] chooses from, narrowest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum InstructionSet {
    Portable,
    Avx2,
    Avx512,
}

impl std::fmt::Display for InstructionSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            InstructionSet::Portable => "portable",
            InstructionSet::Avx2 => "AVX2",
            InstructionSet::Avx512 => "AVX-512",
        })
    }
}

/// The widest instruction set [`dispatch`] may use (tests compare each with the
/// others; they must agree bit for bit).
static LIMIT: AtomicU8 = AtomicU8::new(InstructionSet::Avx512 as u8);

/// Caps the instruction set [`dispatch`] uses, process-wide.
pub fn limit_instruction_set(widest: InstructionSet) {
    LIMIT.store(widest as u8, Ordering::Relaxed);
}

/// [`limit_instruction_set`]'s cap now (code that picks its instructions without
/// [`dispatch`] asks it too).
pub fn instruction_set_limit() -> InstructionSet {
    match LIMIT.load(Ordering::Relaxed) {
        x if x >= InstructionSet::Avx512 as u8 => InstructionSet::Avx512,
        x if x >= InstructionSet::Avx2 as u8 => InstructionSet::Avx2,
        _ => InstructionSet::Portable,
    }
}

/// The widest instruction set this CPU has, whatever the cap.
pub fn widest_instruction_set() -> InstructionSet {
    #[cfg(target_arch = "x86_64")]
    {
        if Avx512::detect().is_some() {
            return InstructionSet::Avx512;
        }
        if Avx2::detect().is_some() {
            return InstructionSet::Avx2;
        }
    }
    InstructionSet::Portable
}

/// The widest instruction set this CPU has, within [`limit_instruction_set`]'s cap
/// (in every build; the library's unit tests' `dispatch` runs portable regardless).
pub fn capped_instruction_set() -> InstructionSet {
    widest_instruction_set().min(instruction_set_limit())
}

/// The instruction set [`dispatch`] runs with now: [`capped_instruction_set`].
pub fn instruction_set() -> InstructionSet {
    if cfg!(test) {
        // What the unit tests' `dispatch` runs.
        return InstructionSet::Portable;
    }
    capped_instruction_set()
}

/// Runs `task` with [`instruction_set`].
#[cfg(not(test))]
#[inline]
pub fn dispatch<T: SimdTask>(task: T) -> T::Output {
    match instruction_set() {
        #[cfg(target_arch = "x86_64")]
        InstructionSet::Avx512 => {
            let s = Avx512::detect().expect("detected above");
            // SAFETY: the token proves AVX-512 is present.
            unsafe { run_avx512(task, s) }
        }
        #[cfg(target_arch = "x86_64")]
        InstructionSet::Avx2 => {
            let s = Avx2::detect().expect("detected above");
            // SAFETY: the token proves AVX2 is present.
            unsafe { run_avx2(task, s) }
        }
        _ => task.run(Portable),
    }
}

/// The library's unit tests run tasks portable only: compiled for three instruction
/// sets, the kernels were most of that build's time. [`run_each`] runs every set there,
/// and the integration tests (tests/packet_engine.rs) compare them through the
/// real `dispatch`.
#[cfg(test)]
pub fn dispatch<T: SimdTask>(task: T) -> T::Output {
    task.run(Portable)
}

/// Runs `task` with every instruction set this CPU has, portable first.
#[cfg(test)]
pub(crate) fn run_each<T: SimdTask + Clone>(task: T) -> Vec<T::Output> {
    #[allow(unused_mut)]
    let mut out = vec![task.clone().run(Portable)];
    #[cfg(target_arch = "x86_64")]
    {
        if let Some(s) = Avx2::detect() {
            // SAFETY: detected.
            out.push(unsafe { run_avx2(task.clone(), s) });
        }
        if let Some(s) = Avx512::detect() {
            // SAFETY: detected.
            out.push(unsafe { run_avx512(task, s) });
        }
    }
    out
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512bw,avx512vl,avx2,bmi1,bmi2,lzcnt,popcnt")]
unsafe fn run_avx512<T: SimdTask>(task: T, s: Avx512) -> T::Output {
    task.run(s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
unsafe fn run_avx2<T: SimdTask>(task: T, s: Avx2) -> T::Output {
    task.run(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every operation against the scalar expression it stands for, bit for bit.
    fn check_ops<S: Simd>(s: S) {
        let vals = [
            0.0f32,
            -0.0,
            1.0,
            -1.5,
            3.25e-8,
            1e30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            2.0,
            -7.0,
            0.1,
            1e-40,
            5.5,
            -3.0,
            9.0,
        ];
        let mut other = vals;
        other.rotate_left(5);
        let (a, b) = (F32s::from_array(s, vals), F32s::from_array(s, other));
        let same = |x: [f32; LANES], f: &dyn Fn(f32, f32) -> f32| {
            for i in 0..LANES {
                let want = f(vals[i], other[i]);
                assert!(
                    x[i].to_bits() == want.to_bits() || (x[i].is_nan() && want.is_nan()),
                    "lane {i}: {} vs {want}",
                    x[i]
                );
            }
        };
        same((a + b).to_array(), &|x, y| x + y);
        same((a - b).to_array(), &|x, y| x - y);
        same((a * b).to_array(), &|x, y| x * y);
        same((a / b).to_array(), &|x, y| x / y);
        same(a.min(b).to_array(), &|x, y| if x < y { x } else { y });
        same(a.max(b).to_array(), &|x, y| if x > y { x } else { y });
        same(a.sqrt().to_array(), &|x, _| x.sqrt());
        same(a.abs().to_array(), &|x, _| x.abs());
        same((-a).to_array(), &|x, _| -x);
        same(a.copysign(b).to_array(), &|x, y| x.copysign(y));
        let m = a.lt(b);
        same(F32s::select(m, a, b).to_array(), &|x, y| {
            if x < y {
                x
            } else {
                y
            }
        });
        let fin = a.is_finite();
        let want = (0..LANES)
            .filter(|&i| vals[i].is_finite())
            .map(|i| vals[i])
            .fold(f32::INFINITY, f32::min);
        assert_eq!(a.reduce_min(fin), want);
        assert_eq!(a.reduce_min(Mask::from_bits(s, 0)), f32::INFINITY);
        assert_eq!(a.reduce_min(Mask::from_bits(s, 1 << 3)), vals[3]);
        for i in 0..LANES {
            assert_eq!(a.le(b).bits() >> i & 1 == 1, vals[i] <= other[i]);
            assert_eq!(a.eq(b).bits() >> i & 1 == 1, vals[i] == other[i]);
            assert_eq!(a.is_finite().bits() >> i & 1 == 1, vals[i].is_finite());
            assert_eq!(
                a.sign_negative().bits() >> i & 1 == 1,
                vals[i].is_sign_negative()
            );
        }
        let w: [u64; LANES] =
            std::array::from_fn(|i| 0x9E37_79B9_7F4A_7C15u64.wrapping_mul(i as u64 + 1));
        let x: [u64; LANES] = std::array::from_fn(|i| 0xD1B5_4A32_D192_ED03u64 ^ (i as u64) << 40);
        let (wa, xa) = (U64s::from_array(s, w), U64s::from_array(s, x));
        for i in 0..LANES {
            assert_eq!(wa.wrapping_mul(xa).to_array()[i], w[i].wrapping_mul(x[i]));
            assert_eq!(wa.wrapping_add(xa).to_array()[i], w[i].wrapping_add(x[i]));
            assert_eq!(wa.xor(xa).to_array()[i], w[i] ^ x[i]);
            assert_eq!(wa.or(xa).to_array()[i], w[i] | x[i]);
            assert_eq!(wa.shr::<27>().to_array()[i], w[i] >> 27);
            assert_eq!(wa.shl::<1>().to_array()[i], w[i] << 1);
            assert_eq!(wa.low32().to_array()[i], w[i] as u32);
            let r = (x[i] >> 59) as u32;
            let rot = wa.low32().rotate_right(xa.shr::<59>().low32());
            assert_eq!(rot.to_array()[i], (w[i] as u32).rotate_right(r));
            assert_eq!(wa.low32().shr::<8>().to_array()[i], (w[i] as u32) >> 8);
        }
        let sel = U64s::select(Mask::from_bits(s, 0b101), wa, xa).to_array();
        assert_eq!((sel[0], sel[1], sel[2]), (w[0], x[1], w[2]));
        let bits = 0b1010_0110_0001_1101;
        assert_eq!(Mask::from_bits(s, bits).bits(), bits);
        assert_eq!((!Mask::from_bits(s, bits)).bits(), !bits & ALL_LANES);
        let u = U32s::from_array(s, std::array::from_fn(|i| (i as u32) * 0x0101_0101));
        let v = U32s::splat(s, 0x00ff_00ff);
        let (ua, va) = (u.to_array(), v.to_array());
        for i in 0..LANES {
            assert_eq!((u + v).to_array()[i], ua[i].wrapping_add(va[i]));
            assert_eq!((u & v).to_array()[i], ua[i] & va[i]);
            assert_eq!(u.xor(v).to_array()[i], ua[i] ^ va[i]);
            assert_eq!(
                (u & v).to_f32().to_array()[i],
                (ua[i] & va[i] & 0xff_ffff) as f32
            );
        }
        let table: [u32; 16] = std::array::from_fn(|i| 0x9E37_79B9u32.wrapping_mul(i as u32 + 1));
        for seed in [1u32, 0x8000_0001, 0xdead_beef] {
            let x: [u32; LANES] =
                std::array::from_fn(|i| seed.wrapping_mul(0x2545_F491 ^ i as u32));
            let xa = U32s::from_array(s, x);
            let index = xa.and(U32s::splat(s, 15));
            for i in 0..LANES {
                assert_eq!(xa.reverse_bits().to_array()[i], x[i].reverse_bits());
                assert_eq!(
                    index.lookup16(&table).to_array()[i],
                    table[(x[i] & 15) as usize]
                );
            }
        }
    }

    #[derive(Clone)]
    struct Check;

    impl SimdTask for Check {
        type Output = &'static str;
        fn run<S: Simd>(self, s: S) -> &'static str {
            check_ops(s);
            std::any::type_name::<S>()
        }
    }

    #[test]
    fn every_instruction_set_computes_what_the_scalar_code_does() {
        let ran = run_each(Check);
        assert_eq!(ran[0], std::any::type_name::<Portable>());
        #[cfg(target_arch = "x86_64")]
        assert_eq!(
            ran.len(),
            1 + Avx2::detect().is_some() as usize + Avx512::detect().is_some() as usize
        );
    }
}
