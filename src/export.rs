//! Scene export to Mitsuba 3, so that ember can be measured against a peer on
//! exactly the image it renders (spec semantics, not the course's): the same
//! camera, lights, materials, path-length rule and pixel filter.
//!
//! Meshes go to binary PLY files beside the XML, one per (material, emitter)
//! group, with vertices unshared so per-corner normals survive. The triangle
//! winding is already the spec's front side (the loader orients it), which is
//! also Mitsuba's: area emitters emit toward it and dielectrics are entered
//! through it.

use crate::camera::Camera;
use crate::film::Image;
use crate::image_io::{write_image, ImageIoError};
use crate::integrators::Roulette;
use crate::lights::Light;
use crate::materials::{Bsdf, Material};
use crate::names::{display_from_table, Named};
use crate::scene::{Scene, NO_LIGHT};
use crate::Color;
use glam::Vec3;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// How the exported scene is rendered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MitsubaSettings {
    pub spp: u32,
    /// ember's `-m`: bounces. Mitsuba's `max_depth` counts path segments, so it is `m + 1`.
    pub max_depth: u32,
    /// The bounce from which ember's roulette runs; Mitsuba's `rr_depth` (the same number).
    /// `None` turns roulette off (Mitsuba: `rr_depth` past `max_depth`).
    pub roulette_start: Option<u32>,
    /// Mitsuba's `<sampler>`; `spp` is rounded to a count it takes.
    pub sampler: MitsubaSampler,
}

/// Where Mitsuba's Russian roulette starts (its `rr_depth`) in a benchmark.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MitsubaRoulette {
    /// At ember's own start (`Roulette::default()`), so both do the same work per
    /// sample: the setting for comparing samples/s.
    #[default]
    Ember,
    /// At this `rr_depth`. Mitsuba's own default is 5; where ember's earlier start
    /// spends less time than it adds variance (many samples), Mitsuba at 5 has the
    /// lower error at equal time, so comparisons of error run it too.
    Depth(u32),
}

impl MitsubaRoulette {
    /// Whether this is `rr_depth` at ember's own start while `all` also has `Ember`:
    /// the same renders twice.
    pub fn repeats_ember(self, all: &[MitsubaRoulette]) -> bool {
        let ember = crate::integrators::Roulette::default().start();
        matches!(self, MitsubaRoulette::Depth(d) if Some(d) == ember)
            && all.contains(&MitsubaRoulette::Ember)
    }
}

impl std::str::FromStr for MitsubaRoulette {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "ember" => Ok(MitsubaRoulette::Ember),
            n => n.parse().map(MitsubaRoulette::Depth).map_err(|_| {
                format!("'{s}' is not a roulette start: 'ember' or Mitsuba's rr_depth (a number)")
            }),
        }
    }
}

/// Mitsuba 3's samplers (`ember export --sampler`). Some take only certain counts and
/// round others up ([`MitsubaSampler::sample_count`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MitsubaSampler {
    Independent,
    Stratified,
    /// The default: the lowest error of Mitsuba's samplers in issue 24's measurements
    /// (CBbunny, CBspheres_lambertian, CBspheres), and it takes nearly every count.
    #[default]
    Multijitter,
    Ldsampler,
    Orthogonal,
}

impl Named for MitsubaSampler {
    const WHAT: &'static str = "Mitsuba sampler";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (
            Self::Independent,
            "independent",
            "Independent uniform numbers; any count",
        ),
        (
            Self::Stratified,
            "stratified",
            "Jittered on a k×k grid; squares",
        ),
        (
            Self::Multijitter,
            "multijitter",
            "Correlated multi-jittered (Kensler); a·b with a = ⌊√n⌋, nearly any count",
        ),
        (
            Self::Ldsampler,
            "ldsampler",
            "Scrambled (0, 2)-sequence; squares of powers of two, at least 4",
        ),
        (
            Self::Orthogonal,
            "orthogonal",
            "Orthogonal-array (Bush) sampling; squares of primes, at least 4",
        ),
    ];
}
display_from_table!(MitsubaSampler);

impl MitsubaSampler {
    /// The count Mitsuba 3.9 renders when asked for `spp` (its `set_sample_count`).
    pub fn sample_count(self, spp: u32) -> u32 {
        let spp = spp.max(1);
        let root_up = |spp: u32| (1..).find(|k: &u32| k * k >= spp).unwrap_or(1);
        match self {
            Self::Independent => spp,
            Self::Stratified => root_up(spp).pow(2),
            Self::Multijitter => {
                let b = (spp as f32).sqrt() as u32;
                spp.div_ceil(b) * b
            }
            Self::Ldsampler => root_up(spp).max(2).next_power_of_two().pow(2),
            Self::Orthogonal => {
                let prime = |x: u32| (2..=x / 2).all(|d| !x.is_multiple_of(d));
                (root_up(spp).max(2)..)
                    .find(|&k| prime(k))
                    .unwrap_or(2)
                    .pow(2)
            }
        }
    }
}

impl MitsubaSettings {
    /// The settings that make Mitsuba render what ember renders with `-s spp -m max_depth`
    /// and roulette policy `roulette`, with the default sampler.
    pub fn for_ember(spp: u32, max_depth: u32, roulette: &Roulette) -> Self {
        MitsubaSettings {
            spp,
            max_depth,
            roulette_start: roulette.start(),
            sampler: MitsubaSampler::default(),
        }
    }
}

/// What an export wrote, and what Mitsuba cannot express exactly.
#[derive(Debug, Default)]
pub struct ExportSummary {
    pub files: Vec<PathBuf>,
    pub warnings: Vec<String>,
}

#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{path}: cannot write: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Image(#[from] ImageIoError),
}

/// Rows of the sky map: the horizon falls between two rows, so a tall map keeps
/// Mitsuba's bilinear lookup from blurring the hemisphere's edge by more than 0.1°.
const SKY_ROWS: u32 = 2048;
const SKY_COLUMNS: u32 = 8;

/// Writes `<dir>/<stem>.xml` and its PLY (and sky EXR) files.
pub fn write_mitsuba(
    scene: &Scene,
    camera: &Camera,
    settings: &MitsubaSettings,
    dir: &Path,
    stem: &str,
) -> Result<ExportSummary, ExportError> {
    let mut summary = ExportSummary::default();
    let mut xml = String::new();
    let _ = writeln!(xml, "<?xml version=\"1.0\" encoding=\"utf-8\"?>");
    let _ = writeln!(
        xml,
        "<!-- exported by ember {} -->\n<scene version=\"3.0.0\">",
        env!("CARGO_PKG_VERSION")
    );
    xml += &integrator_xml(settings);
    let spp = settings.sampler.sample_count(settings.spp);
    if spp != settings.spp {
        summary.warnings.push(format!(
            "Mitsuba's {} sampler takes no {} spp; exported {spp}",
            settings.sampler, settings.spp
        ));
    }
    xml += &sensor_xml(camera, settings.sampler.name(), spp, scene);
    let mut texture_files = BTreeMap::new();
    for (g, group) in triangle_groups(scene).into_iter().enumerate() {
        let name = format!("{stem}_mesh{g}.ply");
        let path = dir.join(&name);
        let texture = group_texture(scene, &group);
        write_ply(scene, &group.triangles, texture.is_some(), &path)?;
        summary.files.push(path);
        let emitter = group_emitter(scene, &group);
        let bsdf = match texture {
            Some(t) => {
                let file = match texture_files.get(&group.material) {
                    Some(f) => f,
                    None => {
                        let f = write_texture(scene, group.material, t, dir, stem, &mut summary)?;
                        texture_files.entry(group.material).or_insert(f)
                    }
                };
                textured_bsdf_xml(file, &scene.textures[t as usize], &mut summary.warnings)
            }
            None => bsdf_xml(&group_material(scene, &group), &mut summary.warnings),
        };
        let _ = writeln!(
            xml,
            "  <shape type=\"ply\">\n    <string name=\"filename\" value=\"{name}\"/>\n    \
             <boolean name=\"face_normals\" value=\"{}\"/>\n{}{}  </shape>",
            !group.smooth,
            bsdf,
            emitter.map(area_emitter_xml).unwrap_or_default()
        );
    }
    for s in &scene.spheres {
        let m = scene.materials[s.material as usize];
        let _ = writeln!(
            xml,
            "  <shape type=\"sphere\">\n    <point name=\"center\" {}/>\n    \
             <float name=\"radius\" value=\"{}\"/>\n{}{}  </shape>",
            xyz(s.centre),
            s.radius,
            bsdf_xml(&m, &mut summary.warnings),
            emission_of(&m).map(area_emitter_xml).unwrap_or_default()
        );
    }
    for light in &scene.lights {
        xml += &light_xml(light, dir, stem, &mut summary)?;
    }
    xml += "</scene>\n";
    let path = dir.join(format!("{stem}.xml"));
    crate::image_io::write_atomically(&path, xml.as_bytes()).map_err(|source| ExportError::Io {
        path: path.clone(),
        source,
    })?;
    summary.files.insert(0, path);
    Ok(summary)
}

fn integrator_xml(s: &MitsubaSettings) -> String {
    let max_depth = s.max_depth + 1;
    // ember plays roulette after sampling the BSDF at its `start`-th scattering vertex.
    // Mitsuba 3.9's path.cpp counts that vertex into `depth` after sampling its BSDF and
    // then plays when `depth >= rr_depth`: the same vertex when `rr_depth = start`.
    // (ember spares the vertex at the depth cap; Mitsuba has no setting for that, so
    // there the exported scene plays where ember does not.)
    let rr_depth = s.roulette_start.map_or(max_depth + 1, |b| b);
    format!(
        "  <integrator type=\"path\">\n    <integer name=\"max_depth\" value=\"{max_depth}\"/>\n    \
         <integer name=\"rr_depth\" value=\"{rr_depth}\"/>\n    \
         <boolean name=\"hide_emitters\" value=\"false\"/>\n  </integrator>\n"
    )
}

fn sensor_xml(camera: &Camera, sampler: &str, spp: u32, scene: &Scene) -> String {
    let (hfov, _) = camera.fov_degrees();
    let target = camera.eye + camera.forward;
    // No clipping (spec §4): the near plane far below any scene feature, the far one past it.
    let extent =
        scene.bounds.diagonal().length().max(1.0) + (camera.eye - scene.bounds.centre()).length();
    format!(
        "  <sensor type=\"perspective\">\n    <float name=\"fov\" value=\"{hfov}\"/>\n    \
         <string name=\"fov_axis\" value=\"x\"/>\n    \
         <float name=\"near_clip\" value=\"{}\"/>\n    <float name=\"far_clip\" value=\"{}\"/>\n    \
         <transform name=\"to_world\">\n      <lookat origin=\"{}\" target=\"{}\" up=\"{}\"/>\n    </transform>\n    \
         <sampler type=\"{sampler}\">\n      <integer name=\"sample_count\" value=\"{spp}\"/>\n    </sampler>\n    \
         <film type=\"hdrfilm\">\n      <integer name=\"width\" value=\"{}\"/>\n      \
         <integer name=\"height\" value=\"{}\"/>\n      <string name=\"pixel_format\" value=\"rgb\"/>\n      \
         <string name=\"component_format\" value=\"float32\"/>\n      <rfilter type=\"box\"/>\n    </film>\n  </sensor>\n",
        extent * 1e-7,
        extent * 10.0,
        csv(camera.eye),
        csv(target),
        csv(camera.up),
        camera.width,
        camera.height,
    )
}

/// Triangles that share a material, an emitter and whether they carry normals.
struct TriangleGroup {
    material: u32,
    light: u32,
    smooth: bool,
    triangles: Vec<usize>,
}

fn triangle_groups(scene: &Scene) -> Vec<TriangleGroup> {
    let mut groups: BTreeMap<(u32, u32, bool), Vec<usize>> = BTreeMap::new();
    for (i, t) in scene.triangles.iter().enumerate() {
        groups
            .entry((t.material, t.light, t.n.is_some()))
            .or_default()
            .push(i);
    }
    groups
        .into_iter()
        .map(|((material, light, smooth), triangles)| TriangleGroup {
            material,
            light,
            smooth,
            triangles,
        })
        .collect()
}

fn group_material(scene: &Scene, g: &TriangleGroup) -> Material {
    if g.light != NO_LIGHT {
        // An area light reflects nothing (spec §5).
        return Material::lambertian(Color::ZERO);
    }
    scene.materials[g.material as usize]
}

/// The texture of a group's material, if it has one (area-light surfaces never do).
fn group_texture(scene: &Scene, g: &TriangleGroup) -> Option<u32> {
    if g.light != NO_LIGHT {
        return None;
    }
    scene
        .material_textures
        .get(g.material as usize)
        .copied()
        .flatten()
}

/// Writes `<stem>_tex<material>.exr`: the material's albedo times its texture, in
/// linear colour, so Mitsuba's `bitmap` (which reads EXR as linear) shows exactly
/// the albedo `Scene::albedo` gives, with no product texture needed.
fn write_texture(
    scene: &Scene,
    material: u32,
    texture: u32,
    dir: &Path,
    stem: &str,
    summary: &mut ExportSummary,
) -> Result<String, ExportError> {
    let t = &scene.textures[texture as usize];
    let base = match scene.materials[material as usize].bsdf {
        Bsdf::Lambertian(b) => b.albedo.vec3(),
        _ => Color::ONE,
    };
    let mut img = Image::new(t.width() as u32, t.height() as u32);
    for y in 0..t.height() {
        for x in 0..t.width() {
            img.pixels[y * t.width() + x] = base * t.texel(x, y);
        }
    }
    let name = format!("{stem}_tex{material}.exr");
    let path = dir.join(&name);
    write_image(&img, &path)?;
    summary.files.push(path);
    Ok(name)
}

/// A diffuse BSDF reading `file`, filtered as ember filters (bilinear, texel centres
/// at half-integers, which is Mitsuba's convention too). Mitsuba's PLY loader flips
/// `v` by default (`flip_tex_coords`), so the file's OpenGL-style coordinates, `v = 0`
/// at the image's bottom, are written unchanged.
fn textured_bsdf_xml(
    file: &str,
    t: &crate::texture::Texture,
    warnings: &mut Vec<String>,
) -> String {
    use crate::texture::Wrap;
    let mode = |w: Wrap| match w {
        Wrap::Repeat => "repeat",
        Wrap::Mirror => "mirror",
        Wrap::Clamp => "clamp",
    };
    if t.wrap_s != t.wrap_t {
        warnings.push(format!(
            "texture {}: Mitsuba has one wrap mode for both axes; {} (the s axis's) is used",
            t.source,
            t.wrap_s.name()
        ));
    }
    format!(
        "    <bsdf type=\"twosided\">\n      <bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\">\
         <string name=\"filename\" value=\"{file}\"/><string name=\"filter_type\" value=\"bilinear\"/>\
         <string name=\"wrap_mode\" value=\"{}\"/></texture></bsdf>\n    </bsdf>\n",
        mode(t.wrap_s)
    )
}

fn group_emitter(scene: &Scene, g: &TriangleGroup) -> Option<Color> {
    match scene.lights.get(g.light as usize) {
        Some(Light::Area(area)) => Some(area.radiance),
        _ => emission_of(&scene.materials[g.material as usize]),
    }
}

fn emission_of(m: &Material) -> Option<Color> {
    m.emits().then_some(m.emission)
}

fn area_emitter_xml(radiance: Color) -> String {
    format!(
        "    <emitter type=\"area\">\n      <rgb name=\"radiance\" value=\"{}\"/>\n    </emitter>\n",
        rgb(radiance)
    )
}

/// Mitsuba's BSDF for a material; one-sided Mitsuba BSDFs are wrapped in
/// `twosided` where the spec says both faces behave alike.
fn bsdf_xml(m: &Material, warnings: &mut Vec<String>) -> String {
    let two_sided = |inner: String| {
        format!(
            "    <bsdf type=\"twosided\">\n  {}    </bsdf>\n",
            inner.replace("\n  ", "\n    ")
        )
    };
    match m.bsdf {
        Bsdf::Lambertian(b) => two_sided(format!(
            "  <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"{}\"/></bsdf>\n",
            rgb(b.albedo.vec3())
        )),
        Bsdf::Mirror(b) => two_sided(format!(
            "  <bsdf type=\"conductor\"><string name=\"material\" value=\"none\"/>\
             <rgb name=\"specular_reflectance\" value=\"{}\"/></bsdf>\n",
            rgb(b.reflectance.vec3())
        )),
        Bsdf::Microfacet(c) => two_sided(format!(
            "  <bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"beckmann\"/>\
             <float name=\"alpha\" value=\"{}\"/><rgb name=\"eta\" value=\"{}\"/>\
             <rgb name=\"k\" value=\"{}\"/></bsdf>\n",
            c.alpha,
            rgb(c.eta()),
            rgb(c.k())
        )),
        Bsdf::Glass(b) => dielectric_xml(b.ior, b.reflectance.vec3(), b.transmittance.vec3()),
        Bsdf::Refraction(b) => {
            warnings.push(
                "refraction-only material: Mitsuba's nearest is a dielectric without reflection, \
                 which weights transmission by (1 - Fresnel) where the spec does not"
                    .into(),
            );
            dielectric_xml(b.ior, Color::ZERO, b.transmittance.vec3())
        }
        Bsdf::NonScattering(_) => {
            "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0 0 0\"/></bsdf>\n".into()
        }
    }
}

fn dielectric_xml(ior: f32, reflectance: Color, transmittance: Color) -> String {
    format!(
        "    <bsdf type=\"dielectric\"><float name=\"int_ior\" value=\"{ior}\"/>\
         <float name=\"ext_ior\" value=\"1\"/><rgb name=\"specular_reflectance\" value=\"{}\"/>\
         <rgb name=\"specular_transmittance\" value=\"{}\"/></bsdf>\n",
        rgb(reflectance),
        rgb(transmittance)
    )
}

fn light_xml(
    light: &Light,
    dir: &Path,
    stem: &str,
    summary: &mut ExportSummary,
) -> Result<String, ExportError> {
    Ok(match *light {
        // Area lights are emitted with their triangles.
        Light::Area(_) => String::new(),
        Light::Point {
            position,
            intensity,
        } => format!(
            "  <emitter type=\"point\">\n    <point name=\"position\" {}/>\n    \
             <rgb name=\"intensity\" value=\"{}\"/>\n  </emitter>\n",
            xyz(position),
            rgb(intensity)
        ),
        Light::Spot(spot) => spot_xml(&spot, &mut summary.warnings),
        Light::Directional {
            direction,
            irradiance,
        } => format!(
            "  <emitter type=\"directional\">\n    <vector name=\"direction\" {}/>\n    \
             <rgb name=\"irradiance\" value=\"{}\"/>\n  </emitter>\n",
            xyz(direction),
            rgb(irradiance)
        ),
        Light::Ambient { radiance } => {
            let name = format!("{stem}_sky.exr");
            let path = dir.join(&name);
            write_image(&sky_map(radiance), &path)?;
            summary.files.push(path);
            format!(
                "  <emitter type=\"envmap\">\n    <string name=\"filename\" value=\"{name}\"/>\n  </emitter>\n"
            )
        }
        Light::Environment(ref env) => {
            let name = format!("{stem}_env.exr");
            let path = dir.join(&name);
            write_image(&mitsuba_env_map(env), &path)?;
            summary.files.push(path);
            format!(
                "  <emitter type=\"envmap\">\n    <string name=\"filename\" value=\"{name}\"/>\n  </emitter>\n"
            )
        }
    })
}

/// Mitsuba's `spot`: intensity `I` on the axis, 1 out to `beam_width`, falling
/// linearly in angle to 0 at `cutoff_angle` (both half angles). ember's (COLLADA's)
/// spot is `cos^e θ` inside the half angle `falloff_angle/2`, 0 outside. With `e = 0`
/// the two agree exactly (`beam_width = cutoff_angle` = the half angle). With `e > 0`
/// no linear ramp is `cos^e`: the export uses the ramp from the axis (`beam_width`
/// 0) that crosses ½ where `cos^e θ` does, capped at the half angle, and warns.
fn spot_xml(spot: &crate::lights::SpotLight, warnings: &mut Vec<String>) -> String {
    let half = spot.cutoff_degrees();
    let (cutoff, beam) = if spot.exponent == 0.0 {
        (half, half)
    } else {
        let half_power = 0.5f32.powf(1.0 / spot.exponent).acos().to_degrees();
        warnings.push(format!(
            "spot light (falloff exponent {}): Mitsuba's spot falls off linearly in angle, \
             not as cos^e; approximated by a ramp to 0 at {:.3}°",
            spot.exponent,
            (2.0 * half_power).min(half)
        ));
        ((2.0 * half_power).min(half), 0.0)
    };
    let up = spot.direction.any_orthonormal_vector();
    format!(
        "  <emitter type=\"spot\">\n    <rgb name=\"intensity\" value=\"{}\"/>\n    \
         <float name=\"cutoff_angle\" value=\"{cutoff}\"/>\n    \
         <float name=\"beam_width\" value=\"{beam}\"/>\n    \
         <transform name=\"to_world\">\n      <lookat origin=\"{}\" target=\"{}\" up=\"{}\"/>\n    \
         </transform>\n  </emitter>\n",
        rgb(spot.intensity),
        csv(spot.position),
        csv(spot.position + spot.direction),
        csv(up)
    )
}

/// Texels of the exported environment map per ember texel (each side), so that
/// Mitsuba's bilinear lookup blurs only a thin seam between ember's constant texels.
const ENV_UPSAMPLE_MAX: u32 = 8;
const ENV_COLUMNS_MAX: u32 = 4096;

/// The environment map in Mitsuba's latitude-longitude convention. Rows agree (+Y on
/// top); Mitsuba's column coordinate `u_m = atan2(x, −z)/2π` runs the other way round
/// +Y from ember's (the course's), and `u = (¾ − u_m) mod 1` maps one to the other.
fn mitsuba_env_map(env: &crate::lights::EnvironmentMap) -> Image {
    let k = (ENV_COLUMNS_MAX / env.width()).clamp(1, ENV_UPSAMPLE_MAX);
    let (w, h) = (env.width() * k, env.height() * k);
    let mut img = Image::new(w, h);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        let u_m = ((i as u32 % w) as f32 + 0.5) / w as f32;
        let v = ((i as u32 / w) as f32 + 0.5) / h as f32;
        *p = env.texel(glam::Vec2::new((0.75 - u_m).rem_euclid(1.0), v));
    }
    img
}

/// The hemisphere light as a latitude-longitude map: Mitsuba's rows run from
/// +Y (top) to −Y, so the upper half is `radiance` and the lower half black.
fn sky_map(radiance: Color) -> Image {
    let mut img = Image::new(SKY_COLUMNS, SKY_ROWS);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        let row = i as u32 / SKY_COLUMNS;
        *p = if row < SKY_ROWS / 2 {
            radiance
        } else {
            Color::ZERO
        };
    }
    img
}

/// Binary PLY of the triangles, three vertices each (with normals when the mesh has them,
/// and texture coordinates `u`, `v` when `uv`).
fn write_ply(scene: &Scene, triangles: &[usize], uv: bool, path: &Path) -> Result<(), ExportError> {
    let io = |source| ExportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let smooth = triangles
        .first()
        .is_some_and(|&i| scene.triangles[i].n.is_some());
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n",
        3 * triangles.len()
    );
    if smooth {
        header += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    if uv {
        header += "property float u\nproperty float v\n";
    }
    let _ = write!(
        header,
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        triangles.len()
    );
    let mut bytes = header.into_bytes();
    for &i in triangles {
        let t = &scene.triangles[i];
        for c in 0..3 {
            push_vec(&mut bytes, scene.positions[t.v[c] as usize]);
            if let Some(n) = t.n {
                push_vec(&mut bytes, scene.normals[n[c] as usize]);
            }
            if uv {
                let k = scene.triangle_uvs.get(i).copied().flatten();
                let p = k.map_or(glam::Vec2::ZERO, |k| scene.uvs[k[c] as usize]);
                bytes.extend_from_slice(&p.x.to_le_bytes());
                bytes.extend_from_slice(&p.y.to_le_bytes());
            }
        }
    }
    for f in 0..triangles.len() as i32 {
        bytes.push(3);
        for c in 0..3 {
            bytes.extend_from_slice(&(3 * f + c).to_le_bytes());
        }
    }
    crate::image_io::write_atomically(path, &bytes).map_err(io)
}

fn push_vec(bytes: &mut Vec<u8>, v: Vec3) {
    for x in v.to_array() {
        bytes.extend_from_slice(&x.to_le_bytes());
    }
}

fn xyz(v: Vec3) -> String {
    format!("x=\"{}\" y=\"{}\" z=\"{}\"", v.x, v.y, v.z)
}

fn csv(v: Vec3) -> String {
    format!("{}, {}, {}", v.x, v.y, v.z)
}

fn rgb(c: Color) -> String {
    format!("{} {} {}", c.x, c.y, c.z)
}

#[cfg(test)]
mod tests {
    use super::MitsubaSampler as S;

    /// The counts Mitsuba 3.9's `set_sample_count` gives for the converge bench's
    /// doubling sequence (worked by hand from its sources; tests/export_mitsuba.rs
    /// asks Mitsuba itself when it is installed).
    #[test]
    fn sample_counts_round_as_mitsuba_does() {
        let asked = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512];
        let expect = |s: S, want: [u32; 10]| {
            let got: Vec<u32> = asked.iter().map(|&n| s.sample_count(n)).collect();
            assert_eq!(got, want, "{s}");
        };
        expect(S::Independent, asked);
        expect(S::Stratified, [1, 4, 4, 9, 16, 36, 64, 144, 256, 529]);
        expect(S::Multijitter, [1, 2, 4, 8, 16, 35, 64, 132, 256, 528]);
        expect(S::Ldsampler, [4, 4, 4, 16, 16, 64, 64, 256, 256, 1024]);
        expect(S::Orthogonal, [4, 4, 4, 9, 25, 49, 121, 169, 289, 529]);
    }
}
