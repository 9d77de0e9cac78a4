//! AVX-512 (one 512-bit register per value, `k` masks) and AVX2 (two 256-bit
//! registers per value, vector masks).

use super::{LaneBits, Simd, LANES};
use std::arch::x86_64::*;
use std::sync::OnceLock;

macro_rules! pair {
    ($f:path, $a:expr, $b:expr) => {
        [$f($a[0], $b[0]), $f($a[1], $b[1])]
    };
}

/// AVX-512 (F, DQ, BW, VL): a token that exists only on CPUs that have it.
#[derive(Clone, Copy, Debug)]
pub struct Avx512(());

/// AVX2: a token that exists only on CPUs that have it.
#[derive(Clone, Copy, Debug)]
pub struct Avx2(());

impl Avx512 {
    /// The token, if this CPU has AVX-512. The answer is kept after the first call:
    /// `dispatch` asks twice per traced packet, and the standard library's cache
    /// still costs a check per feature (eighteen per packet; 0.4 % of a CBbunny
    /// render's profile).
    pub fn detect() -> Option<Self> {
        static HAS: OnceLock<bool> = OnceLock::new();
        let ok = *HAS.get_or_init(|| {
            is_x86_feature_detected!("avx512f")
                && is_x86_feature_detected!("avx512dq")
                && is_x86_feature_detected!("avx512bw")
                && is_x86_feature_detected!("avx512vl")
                && Avx2::detect().is_some()
        });
        ok.then_some(Avx512(()))
    }
}

impl Avx2 {
    /// The token, if this CPU has AVX2 (the answer kept, as [`Avx512::detect`]'s).
    pub fn detect() -> Option<Self> {
        static HAS: OnceLock<bool> = OnceLock::new();
        let ok = *HAS.get_or_init(|| {
            is_x86_feature_detected!("avx2")
                && is_x86_feature_detected!("bmi1")
                && is_x86_feature_detected!("bmi2")
                && is_x86_feature_detected!("lzcnt")
                && is_x86_feature_detected!("popcnt")
        });
        ok.then_some(Avx2(()))
    }
}

// SAFETY: the token is only made by `detect`, after checking every feature used.
unsafe impl Simd for Avx512 {
    const AVX2: bool = true;
    const AVX512: bool = true;
    type F = __m512;
    type U = __m512i;
    type M = __mmask16;
    /// Lanes 0-7 and 8-15.
    type W = [__m512i; 2];

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
    unsafe fn f_reduce_min(a: __m512, m: __mmask16) -> f32 {
        // Lanes outside `m`, and NaN lanes, become +∞.
        let keep = m & _mm512_cmp_ps_mask::<_CMP_ORD_Q>(a, a);
        _mm512_reduce_min_ps(_mm512_mask_blend_ps(keep, _mm512_set1_ps(f32::INFINITY), a))
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
    unsafe fn u_shr<const N: u32>(a: __m512i) -> __m512i {
        _mm512_srl_epi32(a, _mm_cvtsi32_si128(N as i32))
    }
    #[inline(always)]
    unsafe fn u_shl<const N: u32>(a: __m512i) -> __m512i {
        _mm512_sll_epi32(a, _mm_cvtsi32_si128(N as i32))
    }
    #[inline(always)]
    unsafe fn u_mul(a: __m512i, b: __m512i) -> __m512i {
        _mm512_mullo_epi32(a, b)
    }
    #[inline(always)]
    unsafe fn u_rotr(a: __m512i, r: __m512i) -> __m512i {
        _mm512_rorv_epi32(a, r)
    }
    #[inline(always)]
    unsafe fn u_reverse_bits(a: __m512i) -> __m512i {
        let [rev_low, rev_high, bytes] = &REVERSE_TABLES;
        let rev_low = _mm512_broadcast_i32x4(_mm_loadu_si128(rev_low.as_ptr().cast()));
        let rev_high = _mm512_broadcast_i32x4(_mm_loadu_si128(rev_high.as_ptr().cast()));
        let bytes = _mm512_broadcast_i32x4(_mm_loadu_si128(bytes.as_ptr().cast()));
        let nibble = _mm512_set1_epi8(0x0f);
        let low = _mm512_and_si512(a, nibble);
        let high = _mm512_and_si512(_mm512_srli_epi16::<4>(a), nibble);
        let x = _mm512_or_si512(
            _mm512_shuffle_epi8(rev_low, low),
            _mm512_shuffle_epi8(rev_high, high),
        );
        _mm512_shuffle_epi8(x, bytes)
    }
    #[inline(always)]
    unsafe fn u_lookup16(table: &[u32; 16], a: __m512i) -> __m512i {
        _mm512_permutexvar_epi32(a, _mm512_loadu_si512(table.as_ptr().cast()))
    }
    #[inline(always)]
    unsafe fn w_splat(x: u64) -> [__m512i; 2] {
        [_mm512_set1_epi64(x as i64); 2]
    }
    #[inline(always)]
    unsafe fn w_load(a: &[u64; LANES]) -> [__m512i; 2] {
        let p = a.as_ptr();
        [
            _mm512_loadu_si512(p.cast()),
            _mm512_loadu_si512(p.add(8).cast()),
        ]
    }
    #[inline(always)]
    unsafe fn w_store(v: [__m512i; 2], a: &mut [u64; LANES]) {
        let p = a.as_mut_ptr();
        _mm512_storeu_si512(p.cast(), v[0]);
        _mm512_storeu_si512(p.add(8).cast(), v[1]);
    }
    #[inline(always)]
    unsafe fn w_add(a: [__m512i; 2], b: [__m512i; 2]) -> [__m512i; 2] {
        pair!(_mm512_add_epi64, a, b)
    }
    #[inline(always)]
    unsafe fn w_mul(a: [__m512i; 2], b: [__m512i; 2]) -> [__m512i; 2] {
        pair!(_mm512_mullo_epi64, a, b)
    }
    #[inline(always)]
    unsafe fn w_xor(a: [__m512i; 2], b: [__m512i; 2]) -> [__m512i; 2] {
        pair!(_mm512_xor_si512, a, b)
    }
    #[inline(always)]
    unsafe fn w_or(a: [__m512i; 2], b: [__m512i; 2]) -> [__m512i; 2] {
        pair!(_mm512_or_si512, a, b)
    }
    #[inline(always)]
    unsafe fn w_shr<const N: u32>(a: [__m512i; 2]) -> [__m512i; 2] {
        let n = _mm_cvtsi32_si128(N as i32);
        [_mm512_srl_epi64(a[0], n), _mm512_srl_epi64(a[1], n)]
    }
    #[inline(always)]
    unsafe fn w_shl<const N: u32>(a: [__m512i; 2]) -> [__m512i; 2] {
        let n = _mm_cvtsi32_si128(N as i32);
        [_mm512_sll_epi64(a[0], n), _mm512_sll_epi64(a[1], n)]
    }
    #[inline(always)]
    unsafe fn w_low(a: [__m512i; 2]) -> __m512i {
        let lo = _mm512_cvtepi64_epi32(a[0]);
        let hi = _mm512_cvtepi64_epi32(a[1]);
        _mm512_inserti64x4::<1>(_mm512_castsi256_si512(lo), hi)
    }
    #[inline(always)]
    unsafe fn w_select(m: __mmask16, a: [__m512i; 2], b: [__m512i; 2]) -> [__m512i; 2] {
        [
            _mm512_mask_blend_epi64(m as __mmask8, b[0], a[0]),
            _mm512_mask_blend_epi64((m >> 8) as __mmask8, b[1], a[1]),
        ]
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
/// Lanes 0-3, 4-7, 8-11, 12-15.
type W4 = [__m256i; 4];

macro_rules! quad {
    ($f:path, $a:expr, $b:expr) => {
        [
            $f($a[0], $b[0]),
            $f($a[1], $b[1]),
            $f($a[2], $b[2]),
            $f($a[3], $b[3]),
        ]
    };
}

/// `x` where `m` is set and `x` is not NaN, else `+∞`.
#[inline(always)]
unsafe fn finite_in(x: __m256, m: __m256) -> __m256 {
    let keep = _mm256_and_ps(m, _mm256_cmp_ps::<_CMP_ORD_Q>(x, x));
    _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), x, keep)
}

/// `x.rotate_right(r)` per 32-bit lane.
#[inline(always)]
unsafe fn rotr32(x: __m256i, r: __m256i) -> __m256i {
    let left = _mm256_sub_epi32(_mm256_set1_epi32(32), r);
    _mm256_or_si256(_mm256_srlv_epi32(x, r), _mm256_sllv_epi32(x, left))
}

/// Byte shuffles that reverse bits: a nibble's reversal placed in the low and in
/// the high half of a byte, and the bytes of each `u32` in reverse order.
const REVERSE_TABLES: [[u8; 16]; 3] = {
    let mut t = [[0u8; 16]; 3];
    let mut i = 0;
    while i < 16 {
        let r = (i as u8).reverse_bits() >> 4;
        t[0][i] = r << 4;
        t[1][i] = r;
        t[2][i] = (i - i % 4 + 3 - i % 4) as u8;
        i += 1;
    }
    t
};

/// `u32::reverse_bits` per lane: each nibble reversed by table into the other half
/// of its byte, then the bytes reversed.
#[inline(always)]
unsafe fn reverse_bits256(a: __m256i) -> __m256i {
    let [rev_low, rev_high, bytes] = &REVERSE_TABLES;
    let rev_low = _mm256_broadcastsi128_si256(_mm_loadu_si128(rev_low.as_ptr().cast()));
    let rev_high = _mm256_broadcastsi128_si256(_mm_loadu_si128(rev_high.as_ptr().cast()));
    let bytes = _mm256_broadcastsi128_si256(_mm_loadu_si128(bytes.as_ptr().cast()));
    let nibble = _mm256_set1_epi8(0x0f);
    let low = _mm256_and_si256(a, nibble);
    let high = _mm256_and_si256(_mm256_srli_epi16::<4>(a), nibble);
    let x = _mm256_or_si256(
        _mm256_shuffle_epi8(rev_low, low),
        _mm256_shuffle_epi8(rev_high, high),
    );
    _mm256_shuffle_epi8(x, bytes)
}

/// The low 32 bits of the four 64-bit lanes of `x`, then of `y`.
#[inline(always)]
unsafe fn low_halves(x: __m256i, y: __m256i) -> __m256i {
    let even = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
    let lo = _mm256_permutevar8x32_epi32(x, even);
    let hi = _mm256_permutevar8x32_epi32(y, even);
    _mm256_permute2x128_si256::<0x20>(lo, hi)
}

/// `a` where the 32-bit mask lane `m[i]` is set, else `b`, per 64-bit lane `i`.
#[inline(always)]
unsafe fn blend64(m: __m128i, a: __m256i, b: __m256i) -> __m256i {
    let mask = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(m));
    let (a, b) = (_mm256_castsi256_pd(a), _mm256_castsi256_pd(b));
    _mm256_castpd_si256(_mm256_blendv_pd(b, a, mask))
}

/// `a·b mod 2⁶⁴` per 64-bit lane from 32×32→64 products.
#[inline(always)]
unsafe fn mullo64(a: __m256i, b: __m256i) -> __m256i {
    let lo = _mm256_mul_epu32(a, b);
    let cross = _mm256_add_epi64(
        _mm256_mul_epu32(_mm256_srli_epi64::<32>(a), b),
        _mm256_mul_epu32(a, _mm256_srli_epi64::<32>(b)),
    );
    _mm256_add_epi64(lo, _mm256_slli_epi64::<32>(cross))
}

// SAFETY: the token is only made by `detect`, after checking every feature used.
unsafe impl Simd for Avx2 {
    const AVX2: bool = true;
    const AVX512: bool = false;
    type F = F2;
    type U = U2;
    /// Lane masks as all-ones/all-zeros floats.
    type M = F2;
    type W = W4;

    #[inline(always)]
    unsafe fn f_splat(x: f32) -> F2 {
        [_mm256_set1_ps(x); 2]
    }
    #[inline(always)]
    unsafe fn f_load(a: &[f32; LANES]) -> F2 {
        [
            _mm256_loadu_ps(a.as_ptr()),
            _mm256_loadu_ps(a.as_ptr().add(8)),
        ]
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
    unsafe fn f_reduce_min(a: F2, m: F2) -> f32 {
        let v = _mm256_min_ps(finite_in(a[0], m[0]), finite_in(a[1], m[1]));
        let v = _mm_min_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
        let v = _mm_min_ps(v, _mm_movehl_ps(v, v));
        let v = _mm_min_ss(v, _mm_shuffle_ps::<1>(v, v));
        _mm_cvtss_f32(v)
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
    unsafe fn u_shr<const N: u32>(a: U2) -> U2 {
        let n = _mm_cvtsi32_si128(N as i32);
        [_mm256_srl_epi32(a[0], n), _mm256_srl_epi32(a[1], n)]
    }
    #[inline(always)]
    unsafe fn u_shl<const N: u32>(a: U2) -> U2 {
        let n = _mm_cvtsi32_si128(N as i32);
        [_mm256_sll_epi32(a[0], n), _mm256_sll_epi32(a[1], n)]
    }
    #[inline(always)]
    unsafe fn u_mul(a: U2, b: U2) -> U2 {
        pair!(_mm256_mullo_epi32, a, b)
    }
    #[inline(always)]
    unsafe fn u_rotr(a: U2, r: U2) -> U2 {
        pair!(rotr32, a, r)
    }
    #[inline(always)]
    unsafe fn u_reverse_bits(a: U2) -> U2 {
        [reverse_bits256(a[0]), reverse_bits256(a[1])]
    }
    #[inline(always)]
    unsafe fn u_lookup16(table: &[u32; 16], a: U2) -> U2 {
        let low = _mm256_loadu_si256(table.as_ptr().cast());
        let high = _mm256_loadu_si256(table[8..].as_ptr().cast());
        let seven = _mm256_set1_epi32(7);
        let mut out = a;
        for (o, &i) in out.iter_mut().zip(&a) {
            let from_low = _mm256_permutevar8x32_epi32(low, i);
            let from_high = _mm256_permutevar8x32_epi32(high, i);
            *o = _mm256_blendv_epi8(from_low, from_high, _mm256_cmpgt_epi32(i, seven));
        }
        out
    }
    #[inline(always)]
    unsafe fn w_splat(x: u64) -> W4 {
        [_mm256_set1_epi64x(x as i64); 4]
    }
    #[inline(always)]
    unsafe fn w_load(a: &[u64; LANES]) -> W4 {
        let p = a.as_ptr().cast::<__m256i>();
        [
            _mm256_loadu_si256(p),
            _mm256_loadu_si256(p.add(1)),
            _mm256_loadu_si256(p.add(2)),
            _mm256_loadu_si256(p.add(3)),
        ]
    }
    #[inline(always)]
    unsafe fn w_store(v: W4, a: &mut [u64; LANES]) {
        let p = a.as_mut_ptr().cast::<__m256i>();
        for (i, x) in v.iter().enumerate() {
            _mm256_storeu_si256(p.add(i), *x);
        }
    }
    #[inline(always)]
    unsafe fn w_add(a: W4, b: W4) -> W4 {
        quad!(_mm256_add_epi64, a, b)
    }
    #[inline(always)]
    unsafe fn w_mul(a: W4, b: W4) -> W4 {
        quad!(mullo64, a, b)
    }
    #[inline(always)]
    unsafe fn w_xor(a: W4, b: W4) -> W4 {
        quad!(_mm256_xor_si256, a, b)
    }
    #[inline(always)]
    unsafe fn w_or(a: W4, b: W4) -> W4 {
        quad!(_mm256_or_si256, a, b)
    }
    #[inline(always)]
    unsafe fn w_shr<const N: u32>(a: W4) -> W4 {
        let n = _mm_cvtsi32_si128(N as i32);
        [
            _mm256_srl_epi64(a[0], n),
            _mm256_srl_epi64(a[1], n),
            _mm256_srl_epi64(a[2], n),
            _mm256_srl_epi64(a[3], n),
        ]
    }
    #[inline(always)]
    unsafe fn w_shl<const N: u32>(a: W4) -> W4 {
        let n = _mm_cvtsi32_si128(N as i32);
        [
            _mm256_sll_epi64(a[0], n),
            _mm256_sll_epi64(a[1], n),
            _mm256_sll_epi64(a[2], n),
            _mm256_sll_epi64(a[3], n),
        ]
    }
    #[inline(always)]
    unsafe fn w_low(a: W4) -> U2 {
        [low_halves(a[0], a[1]), low_halves(a[2], a[3])]
    }
    #[inline(always)]
    unsafe fn w_select(m: F2, a: W4, b: W4) -> W4 {
        // Each 32-bit mask lane widened to the 64-bit lane it covers.
        let (m0, m1) = (_mm256_castps_si256(m[0]), _mm256_castps_si256(m[1]));
        [
            blend64(_mm256_castsi256_si128(m0), a[0], b[0]),
            blend64(_mm256_extracti128_si256::<1>(m0), a[1], b[1]),
            blend64(_mm256_castsi256_si128(m1), a[2], b[2]),
            blend64(_mm256_extracti128_si256::<1>(m1), a[3], b[3]),
        ]
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
