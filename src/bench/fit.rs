//! Least-squares growth fits for the scaling benchmark: how build time and
//! per-ray time grow with the triangle count.

/// `y = intercept + slope·x`, with the coefficient of determination of the fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearFit {
    pub intercept: f64,
    pub slope: f64,
    pub r2: f64,
}

/// `y = coefficient·N^exponent`, fitted as a line on log-log axes (so every point
/// weighs by its relative error); `r2` is that of the log-log line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerLawFit {
    pub coefficient: f64,
    pub exponent: f64,
    pub r2: f64,
}

/// `y = coefficient·N·log2 N` through the origin: the cost of a top-down build
/// that touches every primitive once per level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NLogNFit {
    pub coefficient: f64,
    pub r2: f64,
}

/// Ordinary least squares; None with fewer than two distinct `x` or non-finite input.
pub fn linear_fit(points: &[(f64, f64)]) -> Option<LinearFit> {
    if points.len() < 2 || points.iter().any(|(x, y)| !x.is_finite() || !y.is_finite()) {
        return None;
    }
    let n = points.len() as f64;
    let mean_x = points.iter().map(|p| p.0).sum::<f64>() / n;
    let mean_y = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mean_x).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    let intercept = mean_y - slope * mean_x;
    let r2 = r_squared(points, |x| intercept + slope * x);
    Some(LinearFit {
        intercept,
        slope,
        r2,
    })
}

/// Power law through points with positive coordinates (others are skipped).
pub fn power_law_fit(points: &[(f64, f64)]) -> Option<PowerLawFit> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let line = linear_fit(&logs)?;
    Some(PowerLawFit {
        coefficient: line.intercept.exp(),
        exponent: line.slope,
        r2: line.r2,
    })
}

/// `a·N·log2 N` minimising the squared error in `y`; points with `N ≤ 1` carry
/// no information about `a` and are skipped.
pub fn n_log_n_fit(points: &[(f64, f64)]) -> Option<NLogNFit> {
    let used: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.0 > 1.0).collect();
    if used.is_empty() || used.iter().any(|(x, y)| !x.is_finite() || !y.is_finite()) {
        return None;
    }
    let basis = |n: f64| n * n.log2();
    let sxy: f64 = used.iter().map(|&(n, y)| basis(n) * y).sum();
    let sxx: f64 = used.iter().map(|&(n, _)| basis(n).powi(2)).sum();
    let coefficient = sxy / sxx;
    let r2 = r_squared(&used, |n| coefficient * basis(n));
    Some(NLogNFit { coefficient, r2 })
}

/// `y = c + d·log2 N` (the traversal cost of a balanced tree).
pub fn log2_fit(points: &[(f64, f64)]) -> Option<LinearFit> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.0 > 0.0)
        .map(|&(n, y)| (n.log2(), y))
        .collect();
    linear_fit(&logs)
}

/// `y = c + d·log2 N` with `c ≥ 0` and `d ≥ 0`, by non-negative least squares: a
/// time per ray is never negative, not even extrapolated to one triangle, and does
/// not fall as the tree deepens. The problem is convex, so the free fit is the answer
/// when it keeps both signs; otherwise the answer lies on a bound: the best line
/// through the origin (`c = 0`) or the best constant (`d = 0`), whichever fits better.
pub fn log2_fit_nonnegative(points: &[(f64, f64)]) -> Option<LinearFit> {
    let free = log2_fit(points)?;
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.0 > 0.0)
        .map(|&(n, y)| (n.log2(), y))
        .collect();
    if free.intercept >= 0.0 && free.slope >= 0.0 {
        return Some(free);
    }
    let sxx: f64 = logs.iter().map(|p| p.0 * p.0).sum();
    let sxy: f64 = logs.iter().map(|p| p.0 * p.1).sum();
    let mean = logs.iter().map(|p| p.1).sum::<f64>() / logs.len() as f64;
    let candidates = [
        (0.0, if sxx > 0.0 { (sxy / sxx).max(0.0) } else { 0.0 }),
        (mean.max(0.0), 0.0),
    ];
    let sse =
        |(c, d): (f64, f64)| -> f64 { logs.iter().map(|&(x, y)| (y - c - d * x).powi(2)).sum() };
    let (intercept, slope) = candidates
        .into_iter()
        .min_by(|a, b| sse(*a).total_cmp(&sse(*b)))
        .expect("two candidates");
    Some(LinearFit {
        intercept,
        slope,
        r2: r_squared(&logs, |x| intercept + slope * x),
    })
}

/// `1 − SS_res/SS_tot`; 1 when the data are constant and matched exactly.
fn r_squared(points: &[(f64, f64)], model: impl Fn(f64) -> f64) -> f64 {
    let mean = points.iter().map(|p| p.1).sum::<f64>() / points.len() as f64;
    let ss_res: f64 = points.iter().map(|&(x, y)| (y - model(x)).powi(2)).sum();
    let ss_tot: f64 = points.iter().map(|&(_, y)| (y - mean).powi(2)).sum();
    if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else if ss_res == 0.0 {
        1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SIZES: [f64; 7] = [1e3, 4e3, 16e3, 64e3, 256e3, 1e6, 4e6];

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    #[test]
    fn exact_n_log_n_recovers_its_coefficient() {
        let pts: Vec<_> = SIZES.iter().map(|&n| (n, 3.5e-5 * n * n.log2())).collect();
        let fit = n_log_n_fit(&pts).unwrap();
        assert!(close(fit.coefficient, 3.5e-5, 1e-12), "{fit:?}");
        assert!(close(fit.r2, 1.0, 1e-12), "{fit:?}");
    }

    #[test]
    fn n_log_n_fit_of_a_quadratic_is_poor() {
        let pts: Vec<_> = SIZES.iter().map(|&n| (n, n * n)).collect();
        assert!(n_log_n_fit(&pts).unwrap().r2 < 0.99);
    }

    #[test]
    fn power_law_exponent_recovered() {
        let pts: Vec<_> = SIZES.iter().map(|&n| (n, 0.02 * n.powf(1.05))).collect();
        let fit = power_law_fit(&pts).unwrap();
        assert!(close(fit.exponent, 1.05, 1e-10), "{fit:?}");
        assert!(close(fit.coefficient, 0.02, 1e-9), "{fit:?}");
        assert!(close(fit.r2, 1.0, 1e-12), "{fit:?}");
    }

    #[test]
    fn n_log_n_data_looks_slightly_superlinear() {
        // Over 1k..4M, N·log2 N is a power law of exponent ≈ 1 + 1/ln(N) ≈ 1.08.
        let pts: Vec<_> = SIZES.iter().map(|&n| (n, n * n.log2())).collect();
        let fit = power_law_fit(&pts).unwrap();
        assert!(fit.exponent > 1.05 && fit.exponent < 1.12, "{fit:?}");
    }

    #[test]
    fn log2_fit_recovers_c_and_d() {
        let pts: Vec<_> = SIZES.iter().map(|&n| (n, 40.0 + 7.5 * n.log2())).collect();
        let fit = log2_fit(&pts).unwrap();
        assert!(close(fit.intercept, 40.0, 1e-10), "{fit:?}");
        assert!(close(fit.slope, 7.5, 1e-10), "{fit:?}");
        assert!(close(fit.r2, 1.0, 1e-12), "{fit:?}");
    }

    #[test]
    fn nonnegative_log2_fit_keeps_a_free_fit_that_is_already_nonnegative() {
        let pts: Vec<_> = SIZES.iter().map(|&n| (n, 40.0 + 7.5 * n.log2())).collect();
        assert_eq!(log2_fit_nonnegative(&pts), log2_fit(&pts));
    }

    #[test]
    fn nonnegative_log2_fit_never_gives_a_negative_time() {
        // Steep growth from 16k up: the free line crosses zero above one triangle.
        let pts: Vec<_> = [16e3, 64e3, 256e3, 1e6, 4e6]
            .iter()
            .map(|&n: &f64| (n, 10.0 * (n.log2() - 12.0)))
            .collect();
        let free = log2_fit(&pts).unwrap();
        assert!(free.intercept < 0.0, "{free:?}");
        let fit = log2_fit_nonnegative(&pts).unwrap();
        assert!(fit.intercept == 0.0 && fit.slope > 0.0, "{fit:?}");
        // It is the best line through the origin: nudging the slope only adds error.
        let sse = |d: f64| {
            pts.iter()
                .map(|&(n, y)| (y - d * n.log2()).powi(2))
                .sum::<f64>()
        };
        assert!(
            sse(fit.slope) <= sse(fit.slope * 1.001) && sse(fit.slope) <= sse(fit.slope * 0.999)
        );
        // Falling times: the best constant.
        let falling: Vec<_> = SIZES.iter().map(|&n| (n, 100.0 - n.log2())).collect();
        let flat = log2_fit_nonnegative(&falling).unwrap();
        assert_eq!(flat.slope, 0.0);
        let mean = falling.iter().map(|p| p.1).sum::<f64>() / falling.len() as f64;
        assert!(close(flat.intercept, mean, 1e-12), "{flat:?}");
    }

    #[test]
    fn degenerate_input_gives_none() {
        assert!(linear_fit(&[(1.0, 2.0)]).is_none());
        assert!(linear_fit(&[(1.0, 2.0), (1.0, 3.0)]).is_none());
        assert!(power_law_fit(&[(1.0, -2.0), (2.0, 0.0)]).is_none());
        assert!(n_log_n_fit(&[(1.0, 2.0)]).is_none());
        assert!(linear_fit(&[(1.0, f64::NAN), (2.0, 3.0)]).is_none());
    }
}
