//! Lanes as arrays, for CPUs without AVX2 (and as the reference the others match).

use super::{LaneBits, Simd, LANES};

/// The portable instruction set: always available.
#[derive(Clone, Copy, Debug, Default)]
pub struct Portable;

type Fa = [f32; LANES];
type Ua = [u32; LANES];

#[inline(always)]
fn map2<T: Copy, R>(a: [T; LANES], b: [T; LANES], f: impl Fn(T, T) -> R) -> [R; LANES] {
    std::array::from_fn(|i| f(a[i], b[i]))
}

#[inline(always)]
fn mask(a: Fa, b: Fa, f: impl Fn(f32, f32) -> bool) -> LaneBits {
    (0..LANES).fold(0, |m, i| m | (f(a[i], b[i]) as LaneBits) << i)
}

// SAFETY: plain Rust; available everywhere.
unsafe impl Simd for Portable {
    const AVX2: bool = false;
    const AVX512: bool = false;
    type F = Fa;
    type U = Ua;
    type M = LaneBits;
    type W = [u64; LANES];

    #[inline(always)]
    unsafe fn f_splat(x: f32) -> Fa {
        [x; LANES]
    }
    #[inline(always)]
    unsafe fn f_load(a: &Fa) -> Fa {
        *a
    }
    #[inline(always)]
    unsafe fn f_store(v: Fa, a: &mut Fa) {
        *a = v;
    }
    #[inline(always)]
    unsafe fn f_add(a: Fa, b: Fa) -> Fa {
        map2(a, b, |x, y| x + y)
    }
    #[inline(always)]
    unsafe fn f_sub(a: Fa, b: Fa) -> Fa {
        map2(a, b, |x, y| x - y)
    }
    #[inline(always)]
    unsafe fn f_mul(a: Fa, b: Fa) -> Fa {
        map2(a, b, |x, y| x * y)
    }
    #[inline(always)]
    unsafe fn f_div(a: Fa, b: Fa) -> Fa {
        map2(a, b, |x, y| x / y)
    }
    #[inline(always)]
    unsafe fn f_sqrt(a: Fa) -> Fa {
        a.map(f32::sqrt)
    }
    #[inline(always)]
    unsafe fn f_min(a: Fa, b: Fa) -> Fa {
        map2(a, b, |x, y| if x < y { x } else { y })
    }
    #[inline(always)]
    unsafe fn f_max(a: Fa, b: Fa) -> Fa {
        map2(a, b, |x, y| if x > y { x } else { y })
    }
    #[inline(always)]
    unsafe fn f_lt(a: Fa, b: Fa) -> LaneBits {
        mask(a, b, |x, y| x < y)
    }
    #[inline(always)]
    unsafe fn f_le(a: Fa, b: Fa) -> LaneBits {
        mask(a, b, |x, y| x <= y)
    }
    #[inline(always)]
    unsafe fn f_eq(a: Fa, b: Fa) -> LaneBits {
        mask(a, b, |x, y| x == y)
    }
    #[inline(always)]
    unsafe fn f_select(m: LaneBits, a: Fa, b: Fa) -> Fa {
        std::array::from_fn(|i| if m >> i & 1 != 0 { a[i] } else { b[i] })
    }
    #[inline(always)]
    unsafe fn f_reduce_min(a: Fa, m: LaneBits) -> f32 {
        (0..LANES)
            .filter(|&i| m >> i & 1 != 0)
            .fold(f32::INFINITY, |b, i| b.min(a[i]))
    }
    #[inline(always)]
    unsafe fn f_to_bits(a: Fa) -> Ua {
        a.map(f32::to_bits)
    }
    #[inline(always)]
    unsafe fn f_from_bits(a: Ua) -> Fa {
        a.map(f32::from_bits)
    }
    #[inline(always)]
    unsafe fn u_to_f(a: Ua) -> Fa {
        a.map(|x| x as i32 as f32)
    }
    #[inline(always)]
    unsafe fn u_splat(x: u32) -> Ua {
        [x; LANES]
    }
    #[inline(always)]
    unsafe fn u_load(a: &Ua) -> Ua {
        *a
    }
    #[inline(always)]
    unsafe fn u_store(v: Ua, a: &mut Ua) {
        *a = v;
    }
    #[inline(always)]
    unsafe fn u_add(a: Ua, b: Ua) -> Ua {
        map2(a, b, u32::wrapping_add)
    }
    #[inline(always)]
    unsafe fn u_and(a: Ua, b: Ua) -> Ua {
        map2(a, b, |x, y| x & y)
    }
    #[inline(always)]
    unsafe fn u_or(a: Ua, b: Ua) -> Ua {
        map2(a, b, |x, y| x | y)
    }
    #[inline(always)]
    unsafe fn u_xor(a: Ua, b: Ua) -> Ua {
        map2(a, b, |x, y| x ^ y)
    }
    #[inline(always)]
    unsafe fn u_eq(a: Ua, b: Ua) -> LaneBits {
        (0..LANES).fold(0, |m, i| m | ((a[i] == b[i]) as LaneBits) << i)
    }
    #[inline(always)]
    unsafe fn u_select(m: LaneBits, a: Ua, b: Ua) -> Ua {
        std::array::from_fn(|i| if m >> i & 1 != 0 { a[i] } else { b[i] })
    }
    #[inline(always)]
    unsafe fn u_shr<const N: u32>(a: Ua) -> Ua {
        a.map(|x| x >> N)
    }
    #[inline(always)]
    unsafe fn u_shl<const N: u32>(a: Ua) -> Ua {
        a.map(|x| x << N)
    }
    #[inline(always)]
    unsafe fn u_mul(a: Ua, b: Ua) -> Ua {
        map2(a, b, u32::wrapping_mul)
    }
    #[inline(always)]
    unsafe fn u_rotr(a: Ua, r: Ua) -> Ua {
        map2(a, r, u32::rotate_right)
    }
    #[inline(always)]
    unsafe fn u_reverse_bits(a: Ua) -> Ua {
        a.map(u32::reverse_bits)
    }
    #[inline(always)]
    unsafe fn u_lookup16(table: &[u32; 16], a: Ua) -> Ua {
        a.map(|i| table[i as usize])
    }
    #[inline(always)]
    unsafe fn w_splat(x: u64) -> [u64; LANES] {
        [x; LANES]
    }
    #[inline(always)]
    unsafe fn w_load(a: &[u64; LANES]) -> [u64; LANES] {
        *a
    }
    #[inline(always)]
    unsafe fn w_store(v: [u64; LANES], a: &mut [u64; LANES]) {
        *a = v;
    }
    #[inline(always)]
    unsafe fn w_add(a: [u64; LANES], b: [u64; LANES]) -> [u64; LANES] {
        map2(a, b, u64::wrapping_add)
    }
    #[inline(always)]
    unsafe fn w_mul(a: [u64; LANES], b: [u64; LANES]) -> [u64; LANES] {
        map2(a, b, u64::wrapping_mul)
    }
    #[inline(always)]
    unsafe fn w_xor(a: [u64; LANES], b: [u64; LANES]) -> [u64; LANES] {
        map2(a, b, |x, y| x ^ y)
    }
    #[inline(always)]
    unsafe fn w_or(a: [u64; LANES], b: [u64; LANES]) -> [u64; LANES] {
        map2(a, b, |x, y| x | y)
    }
    #[inline(always)]
    unsafe fn w_shr<const N: u32>(a: [u64; LANES]) -> [u64; LANES] {
        a.map(|x| x >> N)
    }
    #[inline(always)]
    unsafe fn w_shl<const N: u32>(a: [u64; LANES]) -> [u64; LANES] {
        a.map(|x| x << N)
    }
    #[inline(always)]
    unsafe fn w_low(a: [u64; LANES]) -> Ua {
        a.map(|x| x as u32)
    }
    #[inline(always)]
    unsafe fn w_select(m: LaneBits, a: [u64; LANES], b: [u64; LANES]) -> [u64; LANES] {
        std::array::from_fn(|i| if m >> i & 1 != 0 { a[i] } else { b[i] })
    }
    #[inline(always)]
    unsafe fn m_and(a: LaneBits, b: LaneBits) -> LaneBits {
        a & b
    }
    #[inline(always)]
    unsafe fn m_or(a: LaneBits, b: LaneBits) -> LaneBits {
        a | b
    }
    #[inline(always)]
    unsafe fn m_not(a: LaneBits) -> LaneBits {
        !a & super::ALL_LANES
    }
    #[inline(always)]
    unsafe fn m_bits(a: LaneBits) -> LaneBits {
        a
    }
    #[inline(always)]
    unsafe fn m_from_bits(bits: LaneBits) -> LaneBits {
        bits & super::ALL_LANES
    }
}
