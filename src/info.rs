//! The text of `ember info`: what the loader made of a scene file, so a user
//! can check counts, lights, materials and the derived camera at a glance; and what
//! an image holds and how ember made it.

use crate::camera::Camera;
use crate::color::compact as v;
use crate::image_io::{ImageIoError, OutputFormat};
use crate::lights::Light;
use crate::scene::{Placement, Scene, NO_LIGHT};
use std::fmt::Write;
use std::path::Path;

/// Human-readable summary of `scene` as rendered at `width × height`.
pub fn scene_info(scene: &Scene, width: u32, height: u32) -> String {
    let mut out = String::new();
    // Writing into a String cannot fail.
    let _ = write_info(&mut out, scene, width, height);
    out
}

fn write_info(out: &mut String, scene: &Scene, width: u32, height: u32) -> std::fmt::Result {
    let light_tris = scene
        .triangles
        .iter()
        .filter(|t| t.light != NO_LIGHT)
        .count();
    writeln!(
        out,
        "triangles: {} ({} mesh, {} area-light)",
        scene.triangles.len(),
        scene.triangles.len() - light_tris,
        light_tris
    )?;
    write_meshes(out, scene)?;
    writeln!(out, "spheres: {}", scene.spheres.len())?;
    writeln!(out, "lights: {}", scene.lights.len())?;
    for (i, l) in scene.lights.iter().enumerate() {
        writeln!(out, "  [{i}] {}", describe_light(l))?;
    }
    writeln!(out, "materials: {}", scene.materials.len())?;
    for (i, m) in scene.materials.iter().enumerate() {
        match scene.material_names.get(i) {
            Some(name) => writeln!(out, "  [{i}] {name}: {}", m.describe())?,
            None => writeln!(out, "  [{i}] {}", m.describe())?,
        }
    }
    writeln!(out, "textures: {}", scene.textures.len())?;
    for (i, t) in scene.textures.iter().enumerate() {
        let users: Vec<String> = scene
            .material_textures
            .iter()
            .enumerate()
            .filter(|(_, m)| **m == Some(i as u32))
            .map(|(k, _)| format!("[{k}]"))
            .collect();
        writeln!(
            out,
            "  [{i}] {}: {}x{}, wrap {}/{}, material {}",
            t.source,
            t.width(),
            t.height(),
            t.wrap_s.name(),
            t.wrap_t.name(),
            users.join(", ")
        )?;
    }
    write_camera(out, scene, width, height)?;
    if scene.bounds.is_empty() {
        writeln!(out, "bounds: empty")?;
    } else {
        writeln!(
            out,
            "bounds: min {} max {} (diagonal {:.6})",
            v(scene.bounds.min),
            v(scene.bounds.max),
            scene.bounds.diagonal().length()
        )?;
    }
    writeln!(out, "warnings: {}", scene.warnings.len())?;
    for w in &scene.warnings {
        writeln!(out, "  {w}")?;
    }
    Ok(())
}

/// One line per mesh instance: its name, triangle count and materials' names.
fn write_meshes(out: &mut String, scene: &Scene) -> std::fmt::Result {
    writeln!(out, "meshes: {}", scene.meshes.len())?;
    for (i, m) in scene.meshes.iter().enumerate() {
        let materials: Vec<String> = m
            .materials
            .iter()
            .map(|&k| match scene.material_names.get(k as usize) {
                Some(name) => format!("[{k}] {name}"),
                None => format!("[{k}]"),
            })
            .collect();
        writeln!(
            out,
            "  [{i}] {}: {} triangles, material {}",
            m.name,
            m.count,
            materials.join(", ")
        )?;
    }
    Ok(())
}

/// The native BVH's shape: nodes, depth, leaf sizes, SAH cost and build time.
pub fn bvh_info(name: &str, s: &crate::accel::bvh::BvhStats, build_ms: f64) -> String {
    format!(
        "{name}: {} nodes ({}-wide), {} leaves of {:.2} primitives on average (at most 4), \
         depth {}, SAH cost {:.2}, built in {build_ms:.1} ms\n",
        s.nodes,
        s.width,
        s.leaves,
        s.prims as f64 / s.leaves.max(1) as f64,
        s.max_depth,
        s.sah_cost
    )
}

fn write_camera(out: &mut String, scene: &Scene, width: u32, height: u32) -> std::fmt::Result {
    let cam = Camera::new(&scene.camera, &scene.bounds, width.max(1), height.max(1));
    let (hfov, vfov) = cam.fov_degrees();
    writeln!(out, "camera ({width}x{height}):")?;
    let (placement, but) = match (scene.camera.placement, scene.camera.position) {
        (Placement::File, Some(_)) => ("the file's camera position", ""),
        (Placement::File, None) => (
            "course rule (the file has no camera)",
            "; the file has no camera, so the course's rule places the eye",
        ),
        (Placement::Course, _) => ("course rule (centre - 1.5 x diagonal x forward)", ""),
    };
    writeln!(out, "  placement: {placement}")?;
    if !scene.placement_reason.is_empty() {
        writeln!(out, "  why: {}{but}", scene.placement_reason)?;
    }
    writeln!(out, "  eye {}", v(cam.eye))?;
    writeln!(out, "  forward {}", v(cam.forward))?;
    writeln!(out, "  up {}", v(cam.up))?;
    writeln!(out, "  hfov {hfov:.5} deg, vfov {vfov:.5} deg")
}

fn describe_light(l: &Light) -> String {
    match *l {
        Light::Area(a) => format!(
            "area: radiance {}, centre {}, size {:.6} x {:.6} (area {:.6}), normal {}",
            v(a.radiance),
            v(a.centre),
            a.ex.length(),
            a.ey.length(),
            a.area(),
            v(a.normal)
        ),
        Light::Point {
            position,
            intensity,
        } => format!(
            "point: intensity {}, position {}",
            v(intensity),
            v(position)
        ),
        Light::Spot(s) => format!(
            "spot: intensity {} on the axis, position {}, direction {}, cone half angle {:.4} deg, falloff exponent {}",
            v(s.intensity),
            v(s.position),
            v(s.direction),
            s.cutoff_degrees(),
            s.exponent
        ),
        Light::Directional {
            direction,
            irradiance,
        } => format!(
            "directional: irradiance {}, direction {}",
            v(irradiance),
            v(direction)
        ),
        Light::Ambient { radiance } => {
            format!("ambient (upper hemisphere): radiance {}", v(radiance))
        }
        Light::Environment(ref env) => format!(
            "environment map: {} ({}x{} latitude-longitude)",
            env.source,
            env.width(),
            env.height()
        ),
    }
}

/// The text of `ember info IMAGE`: size, channels and per-channel statistics of any
/// PNG or EXR, then the settings ember recorded in it (or that it has none).
pub fn image_info(path: &Path) -> Result<String, ImageIoError> {
    let err = |msg: String| ImageIoError::Read {
        path: path.display().to_string(),
        msg,
    };
    let mut out = match OutputFormat::from_path(path)? {
        OutputFormat::Exr => exr_summary(path).map_err(|e| err(e.to_string()))?,
        OutputFormat::Png => png_summary(path).map_err(|e| err(e.to_string()))?,
    };
    let meta = crate::image_io::read_metadata(path)?;
    if meta.entries.iter().any(|(k, _)| k.starts_with("ember.")) {
        out.push_str(&meta.to_text());
    } else {
        out.push_str("not written by ember (no ember.* metadata)\n");
    }
    Ok(out)
}

/// Mean, least and most of one channel's finite values, and how many are not finite.
fn channel_line(name: &str, values: impl Iterator<Item = f32>) -> String {
    let (mut n, mut sum, mut min, mut max, mut nonfinite) = (0u64, 0f64, f32::MAX, f32::MIN, 0u64);
    for v in values {
        if !v.is_finite() {
            nonfinite += 1;
            continue;
        }
        n += 1;
        sum += v as f64;
        min = min.min(v);
        max = max.max(v);
    }
    if n == 0 {
        return format!("  {name}: no finite values ({nonfinite} not finite)\n");
    }
    let extra = match nonfinite {
        0 => String::new(),
        k => format!(", {k} not finite"),
    };
    format!(
        "  {name}: mean {}, min {}, max {}{extra}\n",
        number(sum / n as f64),
        number(min as f64),
        number(max as f64)
    )
}

/// Six decimals without trailing zeros (`0.2`, not `0.20000002`); tiny values in
/// scientific notation, so they do not read as 0.
fn number(x: f64) -> String {
    if x != 0.0 && x.abs() < 1e-3 {
        return format!("{x:.3e}");
    }
    let fixed = format!("{x:.6}");
    fixed
        .trim_end_matches('0')
        .trim_end_matches('.')
        .to_string()
}

/// Every layer's size and channels (name and sample type), with statistics.
fn exr_summary(path: &Path) -> exr::error::Result<String> {
    use exr::image::FlatSamples;
    let image = exr::prelude::read_all_flat_layers_from_file(path)?;
    let mut out = String::new();
    for layer in &image.layer_data {
        let name = layer.attributes.layer_name.as_ref();
        let label = name.map_or(String::new(), |n| format!(" (layer {n})"));
        let channels = &layer.channel_data.list;
        let kinds: Vec<String> = channels
            .iter()
            .map(|c| {
                let kind = match c.sample_data {
                    FlatSamples::F16(_) => "16-bit float",
                    FlatSamples::F32(_) => "32-bit float",
                    FlatSamples::U32(_) => "32-bit unsigned",
                };
                format!("{} ({kind})", c.name)
            })
            .collect();
        out += &format!("size: {}x{}{label}\n", layer.size.0, layer.size.1);
        out += &format!("channels: {}\n", kinds.join(", "));
        for c in channels {
            out += &channel_line(&c.name.to_string(), c.sample_data.values_as_f32());
        }
    }
    Ok(out)
}

/// Size, colour type and statistics of the stored values (0 to 1, sRGB-encoded).
fn png_summary(path: &Path) -> image::ImageResult<String> {
    let img = image::open(path)?;
    let color = img.color();
    let names: &[&str] = match (color.has_color(), color.has_alpha()) {
        (true, true) => &["R", "G", "B", "A"],
        (true, false) => &["R", "G", "B"],
        (false, true) => &["Y", "A"],
        (false, false) => &["Y"],
    };
    let bits = 8 * color.bytes_per_pixel() as usize / color.channel_count() as usize;
    let mut out = format!("size: {}x{}\n", img.width(), img.height());
    out += &format!(
        "channels: {} ({bits}-bit, sRGB-encoded; statistics of the stored values, 0 to 1)\n",
        names.join(", ")
    );
    let rgba = img.to_rgba32f();
    // Grey is stored in R, G and B alike; alpha is always the fourth.
    let index = |k: usize| if names[k] == "A" { 3 } else { k };
    for (k, name) in names.iter().enumerate() {
        out += &channel_line(name, rgba.pixels().map(|p| p[index(k)]));
    }
    Ok(out)
}
