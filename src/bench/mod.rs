//! Benchmarks behind `ember bench`: speed against accuracy, and acceleration-structure
//! cost. Library functions return data, so the CLI only parses options and prints.

pub mod accel;
pub mod chart;
pub mod converge;
pub mod embree_modes;
pub mod fit;
pub mod measure;
pub mod meshes;
pub mod mitsuba;
pub mod render;
pub mod scaling;
pub mod stability;
pub mod table;

/// Median of `samples` (mean of the middle two for an even count); 0 when empty.
pub fn median(samples: &mut [f64]) -> f64 {
    if samples.is_empty() {
        return 0.0;
    }
    samples.sort_by(f64::total_cmp);
    let n = samples.len();
    if n % 2 == 1 {
        samples[n / 2]
    } else {
        0.5 * (samples[n / 2 - 1] + samples[n / 2])
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(super::median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(super::median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(super::median(&mut []), 0.0);
    }
}
