//! Will a render fit in memory? The film and the per-pixel results are allocated up
//! front, so the peak is known before rendering: [`render_bytes`] estimates it and
//! [`available_bytes`] says what the machine (and its cgroup limit) leaves free.

use super::adaptive::PixelStats;
use crate::Color;

/// Bytes per pixel that live through a render and its write-out: the tile results,
/// the image and its sample counts, the encoder's or heat map's copy, and with
/// passes the film's sums and counts and each pass's image.
fn bytes_per_pixel(in_passes: bool) -> u64 {
    let result = std::mem::size_of::<PixelStats>() as u64;
    let image = (std::mem::size_of::<Color>() + std::mem::size_of::<u32>()) as u64;
    let single = result + image + image;
    match in_passes {
        false => single,
        true => single + 2 * image,
    }
}

/// Estimated peak bytes of rendering and writing `width × height` pixels, on top of
/// the scene and its acceleration structure (already in memory when this is asked).
pub fn render_bytes(width: u32, height: u32, in_passes: bool) -> u64 {
    // Tiles at the right and bottom edges keep whole-tile slots.
    let tile = super::pixels::TILE;
    let padded = (width.div_ceil(tile) * tile) as u64 * (height.div_ceil(tile) * tile) as u64;
    padded * bytes_per_pixel(in_passes)
}

/// Memory this process may still allocate: the kernel's MemAvailable, capped by the
/// cgroup v2 limit (`memory.max − memory.current`) when one is set. `None` when
/// neither can be read (not Linux).
pub fn available_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|s| {
        s.lines()
            .find_map(|l| l.strip_prefix("MemAvailable:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            .map(|kb| kb * 1024)
    });
    let read = |name: &str| {
        std::fs::read_to_string(format!("/sys/fs/cgroup/{name}"))
            .ok()
            .and_then(|s| s.trim().parse::<u64>().ok())
    };
    // "max" (no limit) does not parse, and leaves the kernel's figure.
    let cgroup =
        read("memory.max").map(|max| max.saturating_sub(read("memory.current").unwrap_or(0)));
    match (meminfo, cgroup) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimate_grows_with_pixels_and_passes() {
        let one = render_bytes(16, 16, false);
        assert_eq!(
            render_bytes(1, 1, false),
            one,
            "a pixel keeps a whole tile slot"
        );
        assert_eq!(render_bytes(1024, 1024, false), one * 4096);
        assert!(render_bytes(16, 16, true) > one);
        // 16384² takes gigabytes: more than a 3 GB limit.
        assert!(render_bytes(16384, 16384, false) > 3 << 30);
    }
}
