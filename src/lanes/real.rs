//! The numbers light transport is written over: `f32`, `u32` and `bool` for one
//! path (`One`), or sixteen lanes of each ([`F32s`], [`U32s`], [`Mask`]) for
//! sixteen paths. Every operation is the IEEE operation its name says, per lane
//! (x86's `min`/`max` conventions included), so a lane computes what the
//! one-path code computes, bit for bit.

use super::simd::{F32s, LaneBits, Mask, Simd, U32s, LANES};
use std::ops::{Add, BitAnd, BitOr, Div, Index, IndexMut, Mul, Neg, Not, Sub};

/// A lane mask: `bool` for one lane.
pub trait LaneMask:
    Copy + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self>
{
    /// Bit `i` set where lane `i` is.
    fn bits(self) -> LaneBits;
    /// The lanes of `bits`, as a mask of `self`'s kind.
    fn mask_like(self, bits: LaneBits) -> Self;
    #[inline(always)]
    fn any(self) -> bool {
        self.bits() != 0
    }
}

/// `f32` per lane.
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    type M: LaneMask;
    type U: UInt<M = Self::M, F = Self>;
    /// Lanes per value: 1 or [`LANES`].
    const WIDTH: usize;
    /// One `T` per lane: `[T; 1]` or `[T; LANES]`.
    type Array<T: Copy>: Copy + Index<usize, Output = T> + IndexMut<usize>;
    /// `x` in every lane, to be filled in by index. (Not from a closure: one the
    /// compiler leaves out of line loses the instruction set of its caller.)
    fn array_of<T: Copy>(x: T) -> Self::Array<T>;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    /// `if self < o { self } else { o }` (`o` when either is NaN).
    fn min(self, o: Self) -> Self;
    /// `if self > o { self } else { o }` (`o` when either is NaN).
    fn max(self, o: Self) -> Self;
    fn copysign(self, sign: Self) -> Self;
    fn lt(self, o: Self) -> Self::M;
    fn le(self, o: Self) -> Self::M;
    fn eq(self, o: Self) -> Self::M;
    #[inline(always)]
    fn gt(self, o: Self) -> Self::M {
        o.lt(self)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Self::M {
        o.le(self)
    }
    /// Neither NaN nor infinite.
    fn is_finite(self) -> Self::M;
    /// `a` where `m`, else `b`.
    fn select(m: Self::M, a: Self, b: Self) -> Self;
    fn to_bits(self) -> Self::U;
    /// The same lanes' value for another number (a value proves its instruction set).
    fn splat_as(self, x: f32) -> Self;
    /// The lanes as an array (one lane: element 0).
    fn to_array(self) -> [f32; LANES];
    /// Lanes of `self`'s kind from an array (elements past `WIDTH` ignored).
    fn array_like(self, a: [f32; LANES]) -> Self;
    fn lane(self, i: usize) -> f32;
}

/// `u32` per lane, wrapping.
pub trait UInt: Copy + BitAnd<Output = Self> + BitOr<Output = Self> {
    type M: LaneMask;
    type F: Real<M = Self::M, U = Self>;
    fn wrapping_add(self, o: Self) -> Self;
    fn xor(self, o: Self) -> Self;
    fn wrapping_mul(self, o: Self) -> Self;
    fn shr<const N: u32>(self) -> Self;
    fn shl<const N: u32>(self) -> Self;
    fn reverse_bits(self) -> Self;
    fn eq(self, o: Self) -> Self::M;
    fn select(m: Self::M, a: Self, b: Self) -> Self;
    /// Exact below 2²⁴ (`x as f32`).
    fn to_f32(self) -> Self::F;
    fn as_f32_bits(self) -> Self::F;
    fn splat_as(self, x: u32) -> Self;
    fn to_array(self) -> [u32; LANES];
    fn array_like(self, a: [u32; LANES]) -> Self;
    fn lane(self, i: usize) -> u32;
    /// `table[x & 0xff]` per lane.
    #[inline(always)]
    fn lookup_byte(self, table: &[u32; 256]) -> Self {
        let a = self.to_array();
        let mut out = [0u32; LANES];
        for i in 0..LANES {
            out[i] = table[(a[i] & 0xff) as usize];
        }
        self.array_like(out)
    }
}

impl LaneMask for bool {
    #[inline(always)]
    fn bits(self) -> LaneBits {
        self as LaneBits
    }
    #[inline(always)]
    fn mask_like(self, bits: LaneBits) -> Self {
        bits & 1 != 0
    }
}

impl Real for f32 {
    type M = bool;
    type U = u32;
    const WIDTH: usize = 1;
    type Array<T: Copy> = [T; 1];
    #[inline(always)]
    fn array_of<T: Copy>(x: T) -> [T; 1] {
        [x]
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        if self < o {
            self
        } else {
            o
        }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if self > o {
            self
        } else {
            o
        }
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        f32::copysign(self, sign)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn eq(self, o: Self) -> bool {
        self == o
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m {
            a
        } else {
            b
        }
    }
    #[inline(always)]
    fn to_bits(self) -> u32 {
        f32::to_bits(self)
    }
    #[inline(always)]
    fn splat_as(self, x: f32) -> Self {
        x
    }
    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        let mut a = [0.0; LANES];
        a[0] = self;
        a
    }
    #[inline(always)]
    fn array_like(self, a: [f32; LANES]) -> Self {
        a[0]
    }
    #[inline(always)]
    fn lane(self, _: usize) -> f32 {
        self
    }
}

impl UInt for u32 {
    type M = bool;
    type F = f32;
    #[inline(always)]
    fn wrapping_add(self, o: Self) -> Self {
        u32::wrapping_add(self, o)
    }
    #[inline(always)]
    fn xor(self, o: Self) -> Self {
        self ^ o
    }
    #[inline(always)]
    fn wrapping_mul(self, o: Self) -> Self {
        u32::wrapping_mul(self, o)
    }
    #[inline(always)]
    fn shr<const N: u32>(self) -> Self {
        self >> N
    }
    #[inline(always)]
    fn shl<const N: u32>(self) -> Self {
        self << N
    }
    #[inline(always)]
    fn reverse_bits(self) -> Self {
        u32::reverse_bits(self)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> bool {
        self == o
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m {
            a
        } else {
            b
        }
    }
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self as f32
    }
    #[inline(always)]
    fn as_f32_bits(self) -> f32 {
        f32::from_bits(self)
    }
    #[inline(always)]
    fn splat_as(self, x: u32) -> Self {
        x
    }
    #[inline(always)]
    fn to_array(self) -> [u32; LANES] {
        let mut a = [0; LANES];
        a[0] = self;
        a
    }
    #[inline(always)]
    fn array_like(self, a: [u32; LANES]) -> Self {
        a[0]
    }
    #[inline(always)]
    fn lane(self, _: usize) -> u32 {
        self
    }
    #[inline(always)]
    fn lookup_byte(self, table: &[u32; 256]) -> Self {
        table[(self & 0xff) as usize]
    }
}

impl<S: Simd> LaneMask for Mask<S> {
    #[inline(always)]
    fn bits(self) -> LaneBits {
        Mask::bits(self)
    }
    #[inline(always)]
    fn mask_like(self, bits: LaneBits) -> Self {
        Mask::from_bits_like(self, bits)
    }
}

impl<S: Simd> Real for F32s<S> {
    type M = Mask<S>;
    type U = U32s<S>;
    const WIDTH: usize = LANES;
    type Array<T: Copy> = [T; LANES];
    #[inline(always)]
    fn array_of<T: Copy>(x: T) -> [T; LANES] {
        [x; LANES]
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F32s::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        F32s::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        F32s::min(self, o)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        F32s::max(self, o)
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        F32s::copysign(self, sign)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Mask<S> {
        F32s::lt(self, o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> Mask<S> {
        F32s::le(self, o)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> Mask<S> {
        F32s::eq(self, o)
    }
    #[inline(always)]
    fn is_finite(self) -> Mask<S> {
        F32s::is_finite(self)
    }
    #[inline(always)]
    fn select(m: Mask<S>, a: Self, b: Self) -> Self {
        F32s::select(m, a, b)
    }
    #[inline(always)]
    fn to_bits(self) -> U32s<S> {
        F32s::bits(self)
    }
    #[inline(always)]
    fn splat_as(self, x: f32) -> Self {
        F32s::splat_like(self, x)
    }
    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        F32s::to_array(self)
    }
    #[inline(always)]
    fn array_like(self, a: [f32; LANES]) -> Self {
        F32s::from_array_like(self, a)
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        F32s::lane(self, i)
    }
}

impl<S: Simd> UInt for U32s<S> {
    type M = Mask<S>;
    type F = F32s<S>;
    #[inline(always)]
    fn wrapping_add(self, o: Self) -> Self {
        U32s::wrapping_add(self, o)
    }
    #[inline(always)]
    fn xor(self, o: Self) -> Self {
        U32s::xor(self, o)
    }
    #[inline(always)]
    fn wrapping_mul(self, o: Self) -> Self {
        U32s::wrapping_mul(self, o)
    }
    #[inline(always)]
    fn shr<const N: u32>(self) -> Self {
        U32s::shr::<N>(self)
    }
    #[inline(always)]
    fn shl<const N: u32>(self) -> Self {
        U32s::shl::<N>(self)
    }
    #[inline(always)]
    fn reverse_bits(self) -> Self {
        U32s::reverse_bits(self)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> Mask<S> {
        U32s::eq(self, o)
    }
    #[inline(always)]
    fn select(m: Mask<S>, a: Self, b: Self) -> Self {
        U32s::select(m, a, b)
    }
    #[inline(always)]
    fn to_f32(self) -> F32s<S> {
        U32s::to_f32(self)
    }
    #[inline(always)]
    fn as_f32_bits(self) -> F32s<S> {
        U32s::as_f32_bits(self)
    }
    #[inline(always)]
    fn splat_as(self, x: u32) -> Self {
        U32s::splat_like(self, x)
    }
    #[inline(always)]
    fn to_array(self) -> [u32; LANES] {
        U32s::to_array(self)
    }
    #[inline(always)]
    fn array_like(self, a: [u32; LANES]) -> Self {
        U32s::from_array_like(self, a)
    }
    #[inline(always)]
    fn lane(self, i: usize) -> u32 {
        self.to_array()[i]
    }
}
