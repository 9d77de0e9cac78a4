//! AVX-512 (one 512-bit register per value, `k` masks) and AVX2 (two 256-bit
//! registers per value, vector masks).

use super::{LaneBits, Simd, LANES};
use std::arch::x86_64::*;

/// AVX-512 (F, DQ, BW, VL): a token that exists only on CPUs that have it.
#[derive(Clone, Copy, Debug)]
pub struct Avx512(());

/// AVX2: a token that exists only on CPUs that have it.
#[derive(Clone, Copy, Debug)]
pub struct Avx2(());

impl Avx512 {
    /// The token, if this CPU has AVX-512 (detected once; the standard library caches CPUID).
    pub fn detect() -> Option<Self> {
        let ok = is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512dq")
            && is_x86_feature_detected!("avx512bw")
            && is_x86_feature_detected!("avx512vl")
            && Avx2::detect().is_some();
        ok.then_some(Avx512(()))
    }
}

impl Avx2 {
    /// The token, if this CPU has AVX2.
    pub fn detect() -> Option<Self> {
        let ok = is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("bmi1")
            && is_x86_feature_detected!("bmi2")
            && is_x86_feature_detected!("lzcnt")
            && is_x86_feature_detected!("popcnt");
        ok.then_some(Avx2(()))
    }
}

// SAFETY: the token is only made by `detect`, after checking every feature used.
unsafe impl Simd for Avx512 {
    type F = __m512;
    type U = __m512i;
    type M = __mmask16;

    #[inline(always)]
    unsafe fn f_splat(x: f32) -> __m512 {
        _mm512_set1_ps(x)
    }
    #[inline(always)]
    unsafe fn f_load(a: &[f32; LANES]) -> __m512 {
        _mm512_loadu_ps(a.as_ptr())
    }
    #[inline(always)]
    unsafe fn f_store(v: __m512, a: &mut [f32; LANES]) {
        _mm512_storeu_ps(a.as_mut_ptr(), v)
    }
    #[inline(always)]
    unsafe fn f_add(a: __m512, b: __m512) -> __m512 {
        _mm512_add_ps(a, b)
    }
    #[inline(always)]
    unsafe fn f_sub(a: __m512, b: __m512) -> __m512 {
        _mm512_sub_ps(a, b)
    }
    #[inline(always)]
    unsafe fn f_mul(a: __m512, b: __m512) -> __m512 {
        _mm512_mul_ps(a, b)
    }
    #[inline(always)]
    unsafe fn f_div(a: __m512, b: __m512) -> __m512 {
        _mm512_div_ps(a, b)
    }
    #[inline(always)]
    unsafe fn f_sqrt(a: __m512) -> __m512 {
        _mm512_sqrt_ps(a)
    }
    #[inline(always)]
    unsafe fn f_min(a: __m512, b: __m512) -> __m512 {
        _mm512_min_ps(a, b)
    }
    #[inline(always)]
    unsafe fn f_max(a: __m512, b: __m512) -> __m512 {
        _mm512_max_ps(a, b)
    }
    #[inline(always)]
    unsafe fn f_lt(a: __m512, b: __m512) -> __mmask16 {
        _mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn f_le(a: __m512, b: __m512) -> __mmask16 {
        _mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn f_eq(a: __m512, b: __m512) -> __mmask16 {
        _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn f_select(m: __mmask16, a: __m512, b: __m512) -> __m512 {
        _mm512_mask_blend_ps(m, b, a)
    }
    #[inline(always)]
    unsafe fn f_to_bits(a: __m512) -> __m512i {
        _mm512_castps_si512(a)
    }
    #[inline(always)]
    unsafe fn f_from_bits(a: __m512i) -> __m512 {
        _mm512_castsi512_ps(a)
    }
    #[inline(always)]
    unsafe fn u_to_f(a: __m512i) -> __m512 {
        _mm512_cvtepi32_ps(a)
    }
    #[inline(always)]
    unsafe fn u_splat(x: u32) -> __m512i {
        _mm512_set1_epi32(x as i32)
    }
    #[inline(always)]
    unsafe fn u_load(a: &[u32; LANES]) -> __m512i {
        _mm512_loadu_si512(a.as_ptr().cast())
    }
    #[inline(always)]
    unsafe fn u_store(v: __m512i, a: &mut [u32; LANES]) {
        _mm512_storeu_si512(a.as_mut_ptr().cast(), v)
    }
    #[inline(always)]
    unsafe fn u_add(a: __m512i, b: __m512i) -> __m512i {
        _mm512_add_epi32(a, b)
    }
    #[inline(always)]
    unsafe fn u_and(a: __m512i, b: __m512i) -> __m512i {
        _mm512_and_si512(a, b)
    }
    #[inline(always)]
    unsafe fn u_or(a: __m512i, b: __m512i) -> __m512i {
        _mm512_or_si512(a, b)
    }
    #[inline(always)]
    unsafe fn u_xor(a: __m512i, b: __m512i) -> __m512i {
        _mm512_xor_si512(a, b)
    }
    #[inline(always)]
    unsafe fn u_eq(a: __m512i, b: __m512i) -> __mmask16 {
        _mm512_cmpeq_epi32_mask(a, b)
    }
    #[inline(always)]
    unsafe fn u_select(m: __mmask16, a: __m512i, b: __m512i) -> __m512i {
        _mm512_mask_blend_epi32(m, b, a)
    }
    #[inline(always)]
    unsafe fn m_and(a: __mmask16, b: __mmask16) -> __mmask16 {
        a & b
    }
    #[inline(always)]
    unsafe fn m_or(a: __mmask16, b: __mmask16) -> __mmask16 {
        a | b
    }
    #[inline(always)]
    unsafe fn m_not(a: __mmask16) -> __mmask16 {
        !a
    }
    #[inline(always)]
    unsafe fn m_bits(a: __mmask16) -> LaneBits {
        a as LaneBits
    }
    #[inline(always)]
    unsafe fn m_from_bits(bits: LaneBits) -> __mmask16 {
        bits as __mmask16
    }
}

type F2 = [__m256; 2];
type U2 = [__m256i; 2];

macro_rules! pair {
    ($f:path, $a:expr, $b:expr) => {
        [$f($a[0], $b[0]), $f($a[1], $b[1])]
    };
}

// SAFETY: the token is only made by `detect`, after checking every feature used.
unsafe impl Simd for Avx2 {
    type F = F2;
    type U = U2;
    /// Lane masks as all-ones/all-zeros floats.
    type M = F2;

    #[inline(always)]
    unsafe fn f_splat(x: f32) -> F2 {
        [_mm256_set1_ps(x); 2]
    }
    #[inline(always)]
    unsafe fn f_load(a: &[f32; LANES]) -> F2 {
        [_mm256_loadu_ps(a.as_ptr()), _mm256_loadu_ps(a.as_ptr().add(8))]
    }
    #[inline(always)]
    unsafe fn f_store(v: F2, a: &mut [f32; LANES]) {
        _mm256_storeu_ps(a.as_mut_ptr(), v[0]);
        _mm256_storeu_ps(a.as_mut_ptr().add(8), v[1]);
    }
    #[inline(always)]
    unsafe fn f_add(a: F2, b: F2) -> F2 {
        pair!(_mm256_add_ps, a, b)
    }
    #[inline(always)]
    unsafe fn f_sub(a: F2, b: F2) -> F2 {
        pair!(_mm256_sub_ps, a, b)
    }
    #[inline(always)]
    unsafe fn f_mul(a: F2, b: F2) -> F2 {
        pair!(_mm256_mul_ps, a, b)
    }
    #[inline(always)]
    unsafe fn f_div(a: F2, b: F2) -> F2 {
        pair!(_mm256_div_ps, a, b)
    }
    #[inline(always)]
    unsafe fn f_sqrt(a: F2) -> F2 {
        [_mm256_sqrt_ps(a[0]), _mm256_sqrt_ps(a[1])]
    }
    #[inline(always)]
    unsafe fn f_min(a: F2, b: F2) -> F2 {
        pair!(_mm256_min_ps, a, b)
    }
    #[inline(always)]
    unsafe fn f_max(a: F2, b: F2) -> F2 {
        pair!(_mm256_max_ps, a, b)
    }
    #[inline(always)]
    unsafe fn f_lt(a: F2, b: F2) -> F2 {
        pair!(_mm256_cmp_ps::<_CMP_LT_OQ>, a, b)
    }
    #[inline(always)]
    unsafe fn f_le(a: F2, b: F2) -> F2 {
        pair!(_mm256_cmp_ps::<_CMP_LE_OQ>, a, b)
    }
    #[inline(always)]
    unsafe fn f_eq(a: F2, b: F2) -> F2 {
        pair!(_mm256_cmp_ps::<_CMP_EQ_OQ>, a, b)
    }
    #[inline(always)]
    unsafe fn f_select(m: F2, a: F2, b: F2) -> F2 {
        [
            _mm256_blendv_ps(b[0], a[0], m[0]),
            _mm256_blendv_ps(b[1], a[1], m[1]),
        ]
    }
    #[inline(always)]
    unsafe fn f_to_bits(a: F2) -> U2 {
        [_mm256_castps_si256(a[0]), _mm256_castps_si256(a[1])]
    }
    #[inline(always)]
    unsafe fn f_from_bits(a: U2) -> F2 {
        [_mm256_castsi256_ps(a[0]), _mm256_castsi256_ps(a[1])]
    }
    #[inline(always)]
    unsafe fn u_to_f(a: U2) -> F2 {
        [_mm256_cvtepi32_ps(a[0]), _mm256_cvtepi32_ps(a[1])]
    }
    #[inline(always)]
    unsafe fn u_splat(x: u32) -> U2 {
        [_mm256_set1_epi32(x as i32); 2]
    }
    #[inline(always)]
    unsafe fn u_load(a: &[u32; LANES]) -> U2 {
        let p = a.as_ptr().cast::<__m256i>();
        [_mm256_loadu_si256(p), _mm256_loadu_si256(p.add(1))]
    }
    #[inline(always)]
    unsafe fn u_store(v: U2, a: &mut [u32; LANES]) {
        let p = a.as_mut_ptr().cast::<__m256i>();
        _mm256_storeu_si256(p, v[0]);
        _mm256_storeu_si256(p.add(1), v[1]);
    }
    #[inline(always)]
    unsafe fn u_add(a: U2, b: U2) -> U2 {
        pair!(_mm256_add_epi32, a, b)
    }
    #[inline(always)]
    unsafe fn u_and(a: U2, b: U2) -> U2 {
        pair!(_mm256_and_si256, a, b)
    }
    #[inline(always)]
    unsafe fn u_or(a: U2, b: U2) -> U2 {
        pair!(_mm256_or_si256, a, b)
    }
    #[inline(always)]
    unsafe fn u_xor(a: U2, b: U2) -> U2 {
        pair!(_mm256_xor_si256, a, b)
    }
    #[inline(always)]
    unsafe fn u_eq(a: U2, b: U2) -> F2 {
        let e = pair!(_mm256_cmpeq_epi32, a, b);
        [_mm256_castsi256_ps(e[0]), _mm256_castsi256_ps(e[1])]
    }
    #[inline(always)]
    unsafe fn u_select(m: F2, a: U2, b: U2) -> U2 {
        let (a, b) = (Self::f_from_bits(a), Self::f_from_bits(b));
        Self::f_to_bits(Self::f_select(m, a, b))
    }
    #[inline(always)]
    unsafe fn m_and(a: F2, b: F2) -> F2 {
        pair!(_mm256_and_ps, a, b)
    }
    #[inline(always)]
    unsafe fn m_or(a: F2, b: F2) -> F2 {
        pair!(_mm256_or_ps, a, b)
    }
    #[inline(always)]
    unsafe fn m_not(a: F2) -> F2 {
        let ones = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        [_mm256_xor_ps(a[0], ones), _mm256_xor_ps(a[1], ones)]
    }
    #[inline(always)]
    unsafe fn m_bits(a: F2) -> LaneBits {
        (_mm256_movemask_ps(a[0]) as LaneBits) | (_mm256_movemask_ps(a[1]) as LaneBits) << 8
    }
    #[inline(always)]
    unsafe fn m_from_bits(bits: LaneBits) -> F2 {
        let lanes = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let half = |b: LaneBits| {
            let v = _mm256_and_si256(_mm256_set1_epi32(b as i32 & 0xff), lanes);
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(v, lanes))
        };
        [half(bits), half(bits >> 8)]
    }
}
