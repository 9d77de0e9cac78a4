//! Benchmarks behind `ember bench`: speed against accuracy, and acceleration-structure
//! cost. Every benchmark has the same shape: its `run` returns a report, and the
//! report ([`Report`]) writes its files and gives the summary the command prints,
//! so the CLI only parses options and calls those three.

pub mod accel;
pub mod chart;
pub mod converge;
pub mod cycles;
pub mod embree_modes;
pub mod estimators;
pub mod fit;
pub mod measure;
pub mod meshes;
pub mod mitsuba;
pub mod render;
pub mod render_calls;
pub mod scaling;
pub mod stability;
pub mod table;

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// What a benchmark's result offers the command line once `run` has returned it.
pub trait Report {
    /// Writes the report's files into `out_dir` (created if missing); returns their paths.
    fn write(&self, out_dir: &Path) -> Result<Vec<PathBuf>>;
    /// The text the command prints on stdout.
    fn summary(&self) -> String;
}

/// Creates `dir` (and its parents) for a report's files.
pub fn create_out_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))
}

/// Writes `text` to `path`, naming the file on failure.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("{}: cannot write", path.display()))
}

/// The doubling sequence `first`, 2·`first`, 4·`first`, … up to `max`: the sample
/// counts of the converge bench's points.
pub(crate) fn doubling(first: u32, max: u32) -> impl Iterator<Item = u32> {
    std::iter::successors(Some(first), |n| n.checked_mul(2)).take_while(move |&n| n <= max)
}

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
