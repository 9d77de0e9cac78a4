//! Elementary functions over any lane type, from IEEE operations only (polynomials
//! after Cephes' `sinf`, `logf` and `expf`): the same result in every lane type and on
//! every machine, which libm's functions do not promise. Accuracy is checked in the
//! tests against `f64`.

use super::real::{Real, UInt};

/// Cephes' `sinf`/`cosf` polynomials, for `|x| ≤ π/4` (error below 2e-7 there).
pub const SIN_POLY: [f32; 3] = [-1.951_529_6e-4, 8.332_161e-3, -1.666_665_5e-1];
pub const COS_POLY: [f32; 3] = [2.443_315_7e-5, -1.388_731_6e-3, 4.166_664_6e-2];

/// `(sin x, cos x)` for `|x| ≤ π/4`.
#[inline(always)]
pub fn sin_cos_quarter<F: Real>(x: F) -> (F, F) {
    let z = x * x;
    let sin = ((x.splat_as(SIN_POLY[0]) * z + x.splat_as(SIN_POLY[1])) * z
        + x.splat_as(SIN_POLY[2]))
        * z
        * x
        + x;
    let cos = ((x.splat_as(COS_POLY[0]) * z + x.splat_as(COS_POLY[1])) * z
        + x.splat_as(COS_POLY[2]))
        * z
        * z
        - x.splat_as(0.5) * z
        + x.splat_as(1.0);
    (sin, cos)
}

/// `x` rounded to the nearest integer (ties to even), for `|x| < 2²²`.
#[inline(always)]
pub fn round<F: Real>(x: F) -> F {
    let magic = x.splat_as(12_582_912.0); // 1.5·2²³
    (x + magic) - magic
}

/// `(sin 2πu, cos 2πu)`: the angle is reduced exactly to the nearest quarter turn
/// (`u` needs no π), then the quarter polynomials.
#[inline(always)]
pub fn sin_cos_turns<F: Real>(u: F) -> (F, F) {
    let t = u * u.splat_as(4.0);
    let k = round(t);
    let (s, co) = sin_cos_quarter((t - k) * u.splat_as(std::f32::consts::FRAC_PI_2));
    // Quarter turns k mod 4: (sin, cos) rotated by k·90°.
    let q = (k + u.splat_as(12_582_912.0)).to_bits();
    let one = q.splat_as(1);
    let odd = (q & one).eq(one);
    let two = q.splat_as(2);
    let half = (q & two).eq(two);
    let (s1, c1) = (F::select(odd, co, s), F::select(odd, -s, co));
    (F::select(half, -s1, s1), F::select(half, -c1, c1))
}

/// Natural logarithm of `x > 0` (Cephes `logf`): NaN below 0, `−∞` at 0, `x` for `+∞`.
#[inline(always)]
pub fn ln<F: Real>(x: F) -> F {
    let bits = x.to_bits();
    // x = m·2^e with m in [1, 2) (normal numbers; subnormals are scaled first).
    let tiny = x.lt(x.splat_as(f32::MIN_POSITIVE));
    let xs = F::select(tiny, x * x.splat_as(8_388_608.0), x); // 2²³
    let bits = F::U::select(tiny, xs.to_bits(), bits);
    let exp_bits = bits.shr::<23>() & bits.splat_as(0xff);
    let mant = (bits & bits.splat_as(0x007f_ffff)) | bits.splat_as(0x3f80_0000);
    let mut m = mant.as_f32_bits();
    let mut e =
        exp_bits.to_f32() - x.splat_as(127.0) - F::select(tiny, x.splat_as(23.0), x.splat_as(0.0));
    // Centre the mantissa on 1: m in [√½, √2).
    let big = m.gt(x.splat_as(std::f32::consts::SQRT_2));
    m = F::select(big, m * x.splat_as(0.5), m);
    e = F::select(big, e + x.splat_as(1.0), e);
    let f = m - x.splat_as(1.0);
    let z = f * f;
    let mut y = x.splat_as(7.037_683_6e-2);
    for k in [
        -1.151_461e-1,
        1.167_699_9e-1,
        -1.242_014_1e-1,
        1.424_932_3e-1,
        -1.666_805_8e-1,
        2.000_071_4e-1,
        -2.499_999_4e-1,
        3.333_333e-1,
    ] {
        y = y * f + x.splat_as(k);
    }
    y = y * f * z;
    y = y - x.splat_as(0.5) * z;
    let r = f + y + e * x.splat_as(std::f32::consts::LN_2);
    let zero = x.splat_as(0.0);
    let r = F::select(x.eq(zero), x.splat_as(f32::NEG_INFINITY), r);
    let r = F::select(x.lt(zero) | !x.eq(x), x.splat_as(f32::NAN), r);
    F::select(x.eq(x.splat_as(f32::INFINITY)), x, r)
}

/// `eˣ` (Cephes `expf`): 0 below about −103, `+∞` above about 88.7, NaN for NaN.
#[inline(always)]
pub fn exp<F: Real>(x: F) -> F {
    let xc = x.max(x.splat_as(-103.0)).min(x.splat_as(88.72));
    let k = round(xc * x.splat_as(std::f32::consts::LOG2_E));
    // x − k·ln 2 in two parts, exact for |k| < 2⁸.
    let r = xc - k * x.splat_as(0.693_359_4) + k * x.splat_as(2.121_944_4e-4);
    let z = r * r;
    let mut p = x.splat_as(1.987_569_1e-4);
    for v in [
        1.398_199_9e-3,
        8.333_452e-3,
        4.166_579_6e-2,
        1.666_666_5e-1,
        5e-1,
    ] {
        p = p * r + x.splat_as(v);
    }
    let y = p * z + r + x.splat_as(1.0);
    // y·2^k, as two halves so that 2^k stays a normal number down to k = −149. For an
    // integer j, the low byte of the bits of `(j + 127) + 1.5·2²³` is j's biased exponent.
    let k1 = round(k * x.splat_as(0.5));
    let k2 = k - k1;
    let v = y * pow2(k1) * pow2(k2);
    let v = F::select(x.gt(x.splat_as(88.72)), x.splat_as(f32::INFINITY), v);
    let v = F::select(x.lt(x.splat_as(-103.0)), x.splat_as(0.0), v);
    F::select(x.eq(x), v, x)
}

/// `2^j` for an integer `j` in `[−126, 127]`.
#[inline(always)]
fn pow2<F: Real>(j: F) -> F {
    let bits = (j + j.splat_as(127.0 + 12_582_912.0)).to_bits();
    (bits & bits.splat_as(0xff)).shl::<23>().as_f32_bits()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f32, b: f64) -> f64 {
        if b == 0.0 {
            a.abs() as f64
        } else {
            ((a as f64 - b) / b).abs()
        }
    }

    #[test]
    fn sin_cos_of_turns_is_accurate_over_the_turn() {
        let mut worst = 0.0f64;
        for i in 0..=100_000 {
            let u = i as f32 / 100_000.0;
            let (s, c) = sin_cos_turns(u);
            let a = 2.0 * std::f64::consts::PI * u as f64;
            worst = worst.max((s as f64 - a.sin()).abs());
            worst = worst.max((c as f64 - a.cos()).abs());
        }
        assert!(worst < 4e-7, "worst error {worst:e}");
    }

    #[test]
    fn ln_is_accurate_from_subnormals_to_the_largest_float() {
        let mut worst = 0.0f64;
        let mut x = 1e-44f32;
        while x < 3e38 {
            let want = (x as f64).ln();
            let err = (ln(x) as f64 - want).abs() / want.abs().max(1.0);
            worst = worst.max(err);
            x = (x * 1.000_37).max(f32::from_bits(x.to_bits() + 1));
        }
        assert!(worst < 3e-7, "worst error {worst:e}");
        assert_eq!(ln(0.0f32), f32::NEG_INFINITY);
        assert!(ln(-1.0f32).is_nan() && ln(f32::NAN).is_nan());
        assert_eq!(ln(f32::INFINITY), f32::INFINITY);
        assert_eq!(ln(1.0f32), 0.0);
    }

    #[test]
    fn exp_is_accurate_where_it_is_finite() {
        let mut worst = 0.0f64;
        let mut x = -87.0f32;
        while x < 88.0 {
            worst = worst.max(rel(exp(x), (x as f64).exp()));
            x += 0.000_97;
        }
        assert!(worst < 3e-7, "worst error {worst:e}");
        // Down into the subnormals, absolutely.
        for x in [-90.0f32, -95.0, -100.0, -102.9] {
            assert!((exp(x) as f64 - (x as f64).exp()).abs() < 2e-45, "{x}");
        }
        assert_eq!(exp(-200.0f32), 0.0);
        assert_eq!(exp(100.0f32), f32::INFINITY);
        assert!(exp(f32::NAN).is_nan());
        assert_eq!(exp(0.0f32), 1.0);
    }
}
