//! Piecewise-constant distributions over `[0,1]` and `[0,1]²` (pbrt-v4's
//! `PiecewiseConstant1D` / `PiecewiseConstant2D`): a tabulated non-negative function
//! is sampled in proportion to its value, continuously inside each cell, and the pdf
//! of any point is read back from the same table, so sampler and pdf cannot disagree.

use glam::Vec2;

/// `func` on `n` equal cells of `[0,1]`, with its running integral.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseConstant1D {
    func: Vec<f32>,
    /// `cdf[i]` = mass of cells `0..i`; `cdf[0] = 0`, `cdf[n] = 1`.
    cdf: Vec<f32>,
    /// `∫₀¹ func` (before the all-zero fallback).
    integral: f32,
}

impl PiecewiseConstant1D {
    /// `func` must be non-empty, finite and non-negative (callers validate their input).
    /// An all-zero `func` is sampled uniformly, so sampling never fails.
    pub fn new(func: &[f32]) -> Self {
        assert!(!func.is_empty(), "empty piecewise-constant function");
        let n = func.len();
        let sum: f64 = func.iter().map(|&f| f as f64).sum();
        let integral = (sum / n as f64) as f32;
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0);
        let mut acc = 0.0f64;
        for (i, &f) in func.iter().enumerate() {
            acc += if sum > 0.0 { f as f64 } else { 1.0 };
            let total = if sum > 0.0 { sum } else { n as f64 };
            cdf.push(if i + 1 == n {
                1.0
            } else {
                (acc / total) as f32
            });
        }
        PiecewiseConstant1D {
            func: func.to_vec(),
            cdf,
            integral,
        }
    }

    pub fn len(&self) -> usize {
        self.func.len()
    }

    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// `∫₀¹ func`.
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// A point `x ∈ [0,1)` drawn with density `pdf(x)`, its pdf and its cell.
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        // Last cell whose cdf start is ≤ u (cells of zero mass are never chosen).
        let cell = self.cdf.partition_point(|&c| c <= u).clamp(1, self.len()) - 1;
        let (c0, c1) = (self.cdf[cell], self.cdf[cell + 1]);
        let du = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.5 };
        let x = ((cell as f32 + du.clamp(0.0, 1.0)) / self.len() as f32).min(ONE_MINUS_EPSILON);
        (x, self.cell_pdf(cell), cell)
    }

    /// Density of `x ∈ [0,1]` (clamped into the table).
    pub fn pdf(&self, x: f32) -> f32 {
        self.cell_pdf(self.cell_of(x))
    }

    fn cell_of(&self, x: f32) -> usize {
        ((x * self.len() as f32) as usize).min(self.len() - 1)
    }

    fn cell_pdf(&self, cell: usize) -> f32 {
        (self.cdf[cell + 1] - self.cdf[cell]) * self.len() as f32
    }
}

const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// `func` on a `width × height` grid over `[0,1]²` (row `j` covers `v ∈ [j/h, (j+1)/h)`):
/// a marginal over rows, then a conditional over the chosen row's cells.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseConstant2D {
    rows: Vec<PiecewiseConstant1D>,
    marginal: PiecewiseConstant1D,
}

impl PiecewiseConstant2D {
    /// `func` in row-major order, `width * height` values, both sides ≥ 1.
    pub fn new(func: &[f32], width: usize, height: usize) -> Self {
        assert!(width > 0 && height > 0 && func.len() == width * height);
        let rows: Vec<PiecewiseConstant1D> = func
            .chunks_exact(width)
            .map(PiecewiseConstant1D::new)
            .collect();
        let marginal: Vec<f32> = rows.iter().map(|r| r.integral()).collect();
        PiecewiseConstant2D {
            rows,
            marginal: PiecewiseConstant1D::new(&marginal),
        }
    }

    /// `∫∫ func du dv`.
    pub fn integral(&self) -> f32 {
        self.marginal.integral()
    }

    /// A point `(u, v)` drawn with density `pdf`, and that density.
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, row) = self.marginal.sample(u.y);
        let (x, pdf_u, _) = self.rows[row].sample(u.x);
        (Vec2::new(x, v), pdf_v * pdf_u)
    }

    /// Density of `(u, v)` with respect to area in `[0,1]²`.
    pub fn pdf(&self, p: Vec2) -> f32 {
        let row = self.marginal.cell_of(p.y);
        self.marginal.cell_pdf(row) * self.rows[row].pdf(p.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_d_samples_in_proportion_and_pdf_matches() {
        let d = PiecewiseConstant1D::new(&[1.0, 0.0, 3.0]);
        assert!((d.integral() - 4.0 / 3.0).abs() < 1e-6);
        let (x, pdf, cell) = d.sample(0.1);
        assert_eq!(cell, 0);
        assert!((x - 0.4 / 3.0).abs() < 1e-6);
        assert!((pdf - 0.75).abs() < 1e-6 && (d.pdf(x) - pdf).abs() < 1e-6);
        // The zero cell is never chosen, even at its cdf boundary.
        assert_eq!(d.sample(0.25).2, 2);
        assert_eq!(d.pdf(0.5), 0.0);
        assert!(d.sample(0.999_999_9).0 < 1.0);
    }

    #[test]
    fn all_zero_is_uniform() {
        let d = PiecewiseConstant1D::new(&[0.0; 4]);
        assert_eq!(d.integral(), 0.0);
        assert!((d.pdf(0.3) - 1.0).abs() < 1e-6);
        assert_eq!(d.sample(0.6).2, 2);
    }

    #[test]
    fn two_d_pdf_is_product_and_integrates_to_one() {
        let f = [1.0, 2.0, 0.0, 5.0, 0.5, 0.5];
        let d = PiecewiseConstant2D::new(&f, 3, 2);
        let cell_area = 1.0 / 6.0;
        let total: f32 = (0..2)
            .flat_map(|j| (0..3).map(move |i| (i, j)))
            .map(|(i, j)| d.pdf(Vec2::new((i as f32 + 0.5) / 3.0, (j as f32 + 0.5) / 2.0)))
            .sum::<f32>()
            * cell_area;
        assert!((total - 1.0).abs() < 1e-5);
        // pdf ∝ func: cell (1,0) has twice the density of cell (0,0).
        let p00 = d.pdf(Vec2::new(0.1, 0.1));
        assert!((d.pdf(Vec2::new(0.5, 0.1)) - 2.0 * p00).abs() < 1e-5);
        let (p, pdf) = d.sample(Vec2::new(0.3, 0.7));
        assert!((d.pdf(p) - pdf).abs() < 1e-5);
    }
}
