//! Rendering one image on many machines: parts and their merge.
//!
//! A part is a render of a rectangle of the image (a band of rows, `--shard K/N`) over
//! a range of sample indices (`--spp-offset S -s M`: samples `S..S+M`). Both split the
//! work exactly: a pixel's value depends only on (seed, pixel, sample indices,
//! settings), since every sample draws from its own random stream
//! ([`crate::sampling::Rng::for_sample`]). [`merge`] checks that the parts belong
//! to one render and cover it exactly once, then assembles them:
//!
//! - bands are copied pixel for pixel, so merged bands are bit-identical to the render
//!   of the whole image (adaptive sampling included);
//! - sample ranges of a pixel are averaged weighted by their per-pixel sample counts,
//!   in f64. The samples are exactly those of the single render, but the sum is formed
//!   in another order (per part, then across parts) and rounded to f32 once more, so the
//!   result agrees with the single render to f32 rounding (a few ulp), not bit for bit:
//!   ember accumulates in floating point, not fixed point.

use crate::film::Image;
use crate::image_metadata::ImageMetadata;
use crate::render::PixelRect;
use crate::Color;
use std::fmt;

/// Band `index` of `count` bands of rows (`--shard K/N`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// Parses `K/N` with `0 ≤ K < N`.
    pub fn parse(s: &str) -> Result<Shard, String> {
        let bad = || format!("--shard: expected K/N with 0 <= K < N, got {s:?}");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (u32, u32) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// Rows `floor(K·H/N) .. floor((K+1)·H/N)` of a `width × height` image (empty when N > H
    /// leaves this band no row).
    pub fn rect(&self, width: u32, height: u32) -> PixelRect {
        let row = |k: u32| (k as u64 * height as u64 / self.count as u64) as u32;
        PixelRect {
            x0: 0,
            y0: row(self.index),
            x1: width,
            y1: row(self.index + 1),
        }
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Metadata keys that differ between the parts of one render; every other key must agree.
/// Input files (camera file, environment map) may sit at another path on each machine;
/// their hashes (`KEY.fnv1a64`) are not per part, so their contents must agree.
pub const PER_PART_KEYS: [&str; 11] = [
    "ember.camera_file",
    "ember.command_line",
    "ember.cpu",
    "ember.env_map",
    "ember.pixels_rendered",
    "ember.render_seconds",
    "ember.samples_per_pixel",
    "ember.scene",
    "ember.shard",
    "ember.spp",
    "ember.spp_offset",
];

/// One rendered part: pixels `rect` of a `frame` image over samples
/// `spp_offset .. spp_offset + spp` (read from `meta`), with each pixel's sample count.
#[derive(Clone, Debug)]
pub struct Part {
    /// The file it came from, for error messages.
    pub name: String,
    pub meta: ImageMetadata,
    /// Width and height of the whole image.
    pub frame: (u32, u32),
    pub rect: PixelRect,
    /// `rect`'s pixels, row-major.
    pub image: Image,
    /// Samples taken per pixel of `rect` (the merge weights).
    pub samples: Vec<u32>,
}

/// Why parts do not merge; every message names the file at fault.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum MergeError {
    #[error("no parts to merge")]
    NoParts,
    #[error("{file}: not a part of a sharded render: {why}")]
    NotAPart { file: String, why: String },
    #[error(
        "{file}: {key} is {theirs:?} here but {ours:?} in {first}: parts of different renders"
    )]
    Mismatch {
        file: String,
        first: String,
        key: String,
        ours: String,
        theirs: String,
    },
    #[error("{file}: duplicate of {other} (same pixels and samples)")]
    Duplicate { file: String, other: String },
    #[error(
        "{file}: overlaps {other}: both render pixels {rect} (samples {range} and {other_range})"
    )]
    Overlap {
        file: String,
        rect: String,
        range: String,
        other: String,
        other_range: String,
    },
    #[error("gap: no part covers pixel ({x}, {y}) of the {w}x{h} image")]
    PixelGap { x: u32, y: u32, w: u32, h: u32 },
    #[error("gap: samples {missing} of pixels {rect} are missing (next part: {file})")]
    SampleGap {
        file: String,
        rect: String,
        missing: String,
    },
    #[error("{file}: pixels {rect} have samples 0..{total} but other pixels 0..{expected}")]
    UnevenSamples {
        file: String,
        rect: String,
        total: u32,
        expected: u32,
    },
}

/// Merged parts: the image of the whole frame, each pixel's sample count, and a header.
#[derive(Clone, Debug)]
pub struct Merged {
    pub image: Image,
    pub samples: Vec<u32>,
    pub meta: ImageMetadata,
}

/// Checks that `parts` are one render's parts covering every pixel and the same sample
/// range `0..N` exactly once, and assembles them (see the module documentation).
pub fn merge(parts: &[Part]) -> Result<Merged, MergeError> {
    let first = parts.first().ok_or(MergeError::NoParts)?;
    let ranges = parts
        .iter()
        .map(sample_range)
        .collect::<Result<Vec<_>, _>>()?;
    for p in parts {
        check_header(first, p)?;
    }
    let cells = cells(parts, &ranges)?;
    let total = check_samples(parts, &ranges, &cells)?;
    let (w, h) = first.frame;
    let mut image = Image::new(w, h);
    let mut samples = vec![0u32; (w as usize) * (h as usize)];
    for c in &cells {
        assemble(parts, c, &mut image, &mut samples);
    }
    Ok(Merged {
        image,
        samples,
        meta: merged_meta(parts, total),
    })
}

/// `spp_offset .. spp_offset + spp` of a part, from its header.
fn sample_range(p: &Part) -> Result<(u32, u32), MergeError> {
    let get = |key: &str| -> Result<u32, MergeError> {
        let v = p.meta.get(key).ok_or_else(|| MergeError::NotAPart {
            file: p.name.clone(),
            why: format!("no {key} in its header"),
        })?;
        v.parse().map_err(|_| MergeError::NotAPart {
            file: p.name.clone(),
            why: format!("{key} is {v:?}, not a count"),
        })
    };
    let (offset, spp) = (get("ember.spp_offset")?, get("ember.spp")?);
    let end = offset
        .checked_add(spp)
        .ok_or_else(|| MergeError::NotAPart {
            file: p.name.clone(),
            why: "ember.spp_offset + ember.spp overflows".into(),
        })?;
    let n = p.rect.area() as usize;
    if p.image.pixels.len() != n || p.samples.len() != n {
        return Err(MergeError::NotAPart {
            file: p.name.clone(),
            why: "its pixel data does not match its data window".into(),
        });
    }
    if p.rect.x1 > p.frame.0 || p.rect.y1 > p.frame.1 {
        return Err(MergeError::NotAPart {
            file: p.name.clone(),
            why: format!("pixels {} lie outside the image", rect_text(p.rect)),
        });
    }
    Ok((offset, end))
}

/// Every key outside [`PER_PART_KEYS`] (scene hash, resolution, settings, seed,
/// version, backend) must have the same value in `p` as in `first`.
fn check_header(first: &Part, p: &Part) -> Result<(), MergeError> {
    let shared = |m: &ImageMetadata| -> Vec<(String, String)> {
        let mut v: Vec<_> = m
            .entries
            .iter()
            .filter(|(k, _)| !PER_PART_KEYS.contains(&k.as_str()))
            .cloned()
            .collect();
        v.sort();
        v
    };
    let (a, b) = (shared(&first.meta), shared(&p.meta));
    let keys: std::collections::BTreeSet<&String> = a.iter().chain(&b).map(|(k, _)| k).collect();
    let value = |v: &[(String, String)], k: &String| {
        v.iter()
            .find(|(key, _)| key == k)
            .map_or_else(|| "(absent)".to_string(), |(_, v)| v.clone())
    };
    for k in keys {
        let (ours, theirs) = (value(&a, k), value(&b, k));
        if ours != theirs {
            return Err(MergeError::Mismatch {
                file: p.name.clone(),
                first: first.name.clone(),
                key: k.clone(),
                ours,
                theirs,
            });
        }
    }
    if p.frame != first.frame {
        return Err(MergeError::Mismatch {
            file: p.name.clone(),
            first: first.name.clone(),
            key: "image size".into(),
            ours: format!("{}x{}", first.frame.0, first.frame.1),
            theirs: format!("{}x{}", p.frame.0, p.frame.1),
        });
    }
    Ok(())
}

/// A rectangle of pixels covered by the same parts (sorted by sample offset): the
/// parts' edges cut the image into such cells.
struct Cell {
    rect: PixelRect,
    parts: Vec<usize>,
}

/// Cuts the frame along every part's edges and lists the parts covering each cell.
/// Identical parts (same pixels, same samples) are refused as duplicates.
fn cells(parts: &[Part], ranges: &[(u32, u32)]) -> Result<Vec<Cell>, MergeError> {
    for (i, p) in parts.iter().enumerate() {
        if let Some(j) = (0..i).find(|&j| parts[j].rect == p.rect && ranges[j] == ranges[i]) {
            return Err(MergeError::Duplicate {
                file: p.name.clone(),
                other: parts[j].name.clone(),
            });
        }
    }
    let (w, h) = parts[0].frame;
    let cuts = |ends: &dyn Fn(&PixelRect) -> [u32; 2], last: u32| {
        let mut v: Vec<u32> = parts.iter().flat_map(|p| ends(&p.rect)).collect();
        v.extend([0, last]);
        v.sort_unstable();
        v.dedup();
        v
    };
    let xs = cuts(&|r| [r.x0, r.x1], w);
    let ys = cuts(&|r| [r.y0, r.y1], h);
    let mut out = Vec::new();
    for y in ys.windows(2) {
        for x in xs.windows(2) {
            let rect = PixelRect {
                x0: x[0],
                y0: y[0],
                x1: x[1],
                y1: y[1],
            };
            let mut covering: Vec<usize> = (0..parts.len())
                .filter(|&i| contains(parts[i].rect, rect))
                .collect();
            covering.sort_by_key(|&i| ranges[i]);
            out.push(Cell {
                rect,
                parts: covering,
            });
        }
    }
    Ok(out)
}

/// Every cell's sample ranges must tile `0..N` for the same N everywhere; returns N.
fn check_samples(parts: &[Part], ranges: &[(u32, u32)], cells: &[Cell]) -> Result<u32, MergeError> {
    let (w, h) = parts[0].frame;
    let mut expected: Option<u32> = None;
    for c in cells {
        let Some(&last) = c.parts.last() else {
            return Err(MergeError::PixelGap {
                x: c.rect.x0,
                y: c.rect.y0,
                w,
                h,
            });
        };
        let (mut end, mut prev) = (0u32, c.parts[0]);
        for &i in &c.parts {
            let (s, e) = ranges[i];
            if s < end {
                return Err(MergeError::Overlap {
                    file: parts[i].name.clone(),
                    rect: rect_text(c.rect),
                    range: format!("{s}..{e}"),
                    other: parts[prev].name.clone(),
                    other_range: format!("{}..{}", ranges[prev].0, ranges[prev].1),
                });
            }
            if s > end {
                return Err(MergeError::SampleGap {
                    file: parts[i].name.clone(),
                    rect: rect_text(c.rect),
                    missing: format!("{end}..{s}"),
                });
            }
            (end, prev) = (e, i);
        }
        match expected {
            None => expected = Some(end),
            Some(n) if n != end => {
                return Err(MergeError::UnevenSamples {
                    file: parts[last].name.clone(),
                    rect: rect_text(c.rect),
                    total: end,
                    expected: n,
                })
            }
            Some(_) => {}
        }
    }
    Ok(expected.unwrap_or(0))
}

/// Writes a cell's pixels: a lone part is copied exactly, several are averaged
/// weighted by their sample counts.
fn assemble(parts: &[Part], c: &Cell, image: &mut Image, samples: &mut [u32]) {
    let w = image.width as usize;
    for y in c.rect.y0..c.rect.y1 {
        for x in c.rect.x0..c.rect.x1 {
            let dst = (y as usize) * w + x as usize;
            let src = |p: &Part| {
                ((y - p.rect.y0) as usize) * (p.rect.width() as usize) + (x - p.rect.x0) as usize
            };
            if let [only] = c.parts[..] {
                let p = &parts[only];
                image.pixels[dst] = p.image.pixels[src(p)];
                samples[dst] = p.samples[src(p)];
                continue;
            }
            let (mut sum, mut n) = ([0f64; 3], 0u64);
            for p in c.parts.iter().map(|&i| &parts[i]) {
                let (v, k) = (p.image.pixels[src(p)], p.samples[src(p)] as u64);
                for (s, v) in sum.iter_mut().zip(v.to_array()) {
                    *s += v as f64 * k as f64;
                }
                n += k;
            }
            let d = n.max(1) as f64;
            image.pixels[dst] = Color::new(
                (sum[0] / d) as f32,
                (sum[1] / d) as f32,
                (sum[2] / d) as f32,
            );
            samples[dst] = n.min(u32::MAX as u64) as u32;
        }
    }
}

/// The header the parts agree on (scene, settings, seed, version), the first part's
/// scene path, `ember.spp` = N, the merge's command line, and how many parts it came
/// from with their summed render time.
fn merged_meta(parts: &[Part], total: u32) -> ImageMetadata {
    let first = &parts[0];
    let mut m = ImageMetadata::default();
    for (k, v) in &first.meta.entries {
        if !PER_PART_KEYS.contains(&k.as_str()) || k == "ember.scene" {
            m.push(k.clone(), v);
        }
    }
    m.push("ember.spp", total);
    let args: Vec<String> = std::env::args().collect();
    m.push("ember.merge_command_line", args.join(" "));
    m.push("ember.merged_parts", parts.len());
    let seconds: f64 = parts
        .iter()
        .filter_map(|p| p.meta.get("ember.render_seconds")?.parse::<f64>().ok())
        .sum();
    m.push("ember.parts_render_seconds", format!("{seconds:.3}"));
    m
}

/// Whether `outer` contains all of `inner`.
fn contains(outer: PixelRect, inner: PixelRect) -> bool {
    outer.x0 <= inner.x0 && inner.x1 <= outer.x1 && outer.y0 <= inner.y0 && inner.y1 <= outer.y1
}

fn rect_text(r: PixelRect) -> String {
    format!("x {}..{}, y {}..{}", r.x0, r.x1, r.y0, r.y1)
}
