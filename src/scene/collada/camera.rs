//! `<camera>` → `CameraDesc` (spec §4): view direction, field of view, and the
//! camera node's position, used where the file's own placement applies.

use super::transform::{linear, point};
use super::xml::{child, path, Ctx};
use super::LoadError;
use crate::scene::{CameraDesc, Placement};
use glam::{DMat4, DVec3};
use roxmltree::{Document, Node};

/// The Blender builds that wrote the course's scenes (CS184 and CMU462 sets).
const COURSE_EXPORTERS: [&str; 2] = ["Blender 2.72", "Blender 2.74"];

pub(crate) fn read_camera(
    ctx: &mut Ctx,
    camera: Node,
    w: &DMat4,
    placement: Placement,
) -> Result<CameraDesc, LoadError> {
    let (forward, up) = orientation(ctx, camera, w, placement)?;
    let (tan_half_x, tan_half_y) = field_of_view(ctx, camera)?;
    let position = point(w, DVec3::ZERO).as_vec3();
    Ok(CameraDesc {
        forward,
        up,
        tan_half_x,
        tan_half_y,
        position: position.is_finite().then_some(position),
        placement,
    })
}

/// Whether the course wrote the file, and why that is the answer: then its camera
/// keeps the course's placement (spec §4), else it stands where the author put it.
/// A file is the course's when it uses the course's CGL/CMU462 extension, was
/// written by the Blender builds that wrote every course scene, or names no
/// authoring tool at all (hand-written, as the project's own test scenes are).
pub(crate) fn course_placement(doc: &Document) -> (Placement, String) {
    let extension = doc.descendants().any(|n| {
        n.has_tag_name("technique")
            && n.attribute("profile")
                .is_some_and(|p| p == "CGL" || p == "CMU462")
    });
    if extension {
        return (
            Placement::Course,
            "the file uses the course's CGL/CMU462 extension".into(),
        );
    }
    match authoring_tool(doc) {
        None => (
            Placement::Course,
            "the file names no <authoring_tool>".into(),
        ),
        Some(t) if COURSE_EXPORTERS.iter().any(|c| t.starts_with(c)) => (
            Placement::Course,
            format!(
                "written by \"{}\", the course's exporter",
                super::xml::clip(t)
            ),
        ),
        Some(t) => (
            Placement::File,
            format!(
                "written by \"{}\", not by the course's exporter",
                super::xml::clip(t)
            ),
        ),
    }
}

/// The first `<contributor>`'s `<authoring_tool>`, if it names one.
pub(crate) fn authoring_tool<'a>(doc: &'a Document) -> Option<&'a str> {
    child(doc.root_element(), "asset")
        .into_iter()
        .flat_map(|a| a.children().filter(|c| c.has_tag_name("contributor")))
        .find_map(|c| child(c, "authoring_tool"))
        .and_then(|t| t.text())
        .map(str::trim)
        .filter(|t| !t.is_empty())
}

/// Whether `tool` is Blender 2.80 or later, whose exporter writes a point or spot
/// light's colour times its power in watts (earlier builds: a unitless energy).
pub(crate) fn writes_watts(tool: &str) -> bool {
    let Some(version) = tool.strip_prefix("Blender ") else {
        return false;
    };
    let mut parts = version.split(|c: char| !c.is_ascii_digit());
    let major = parts.next().and_then(|m| m.parse::<u32>().ok());
    let minor = parts.next().and_then(|m| m.parse::<u32>().ok());
    matches!((major, minor), (Some(m), Some(n)) if (m, n) >= (2, 80))
}

/// `F = normalize(W3·(0,0,−1))`; `U` = world +Y made orthogonal to `F`, or
/// `W3·(0,1,0)` when `F` is parallel to +Y.
/// Where the file's placement applies, `U` is the camera's own up `W3·(0,1,0)` made
/// orthogonal to `F`, so a rolled camera keeps its roll.
fn orientation(
    ctx: &Ctx,
    camera: Node,
    w: &DMat4,
    placement: Placement,
) -> Result<(glam::Vec3, glam::Vec3), LoadError> {
    let w3 = linear(w);
    let f = w3 * DVec3::NEG_Z;
    if !f.is_finite() || f.length_squared() == 0.0 {
        return Err(ctx.err(
            camera,
            "the camera node's transform gives no view direction",
        ));
    }
    let f = f.normalize();
    let own_up = (placement == Placement::File)
        .then(|| orthogonal_part(w3 * DVec3::Y, f))
        .flatten();
    let up = own_up
        .or_else(|| orthogonal_part(DVec3::Y, f))
        .or_else(|| orthogonal_part(w3 * DVec3::Y, f))
        .unwrap_or_else(|| f.any_orthonormal_vector());
    Ok((f.as_vec3(), up.as_vec3()))
}

/// `v` minus its component along unit `f`, normalized; `None` if (nearly) parallel.
fn orthogonal_part(v: DVec3, f: DVec3) -> Option<DVec3> {
    let o = v - v.dot(f) * f;
    let len = o.length();
    (len.is_finite() && len > 1e-9 * v.length()).then(|| o / len)
}

/// `tan(xfov/2)`, `tan(yfov/2)`, the missing one derived from `aspect_ratio`.
fn field_of_view(ctx: &mut Ctx, camera: Node) -> Result<(Option<f32>, Option<f32>), LoadError> {
    let Some(persp) = path(camera, &["optics", "technique_common", "perspective"]) else {
        let ortho = path(camera, &["optics", "technique_common", "orthographic"]);
        let msg = match ortho {
            Some(_) => "orthographic cameras are not supported; rendered as a perspective camera with the default field of view",
            None => "no <perspective> optics; using the default field of view",
        };
        ctx.warn(camera, msg);
        let d = CameraDesc::default();
        return Ok((d.tan_half_x, d.tan_half_y));
    };
    let tan_half = |name: &str| -> Result<Option<f32>, LoadError> {
        match ctx.child_scalar(persp, name)? {
            Some(deg) if deg > 0.0 && deg < 180.0 => Ok(Some((deg.to_radians() * 0.5).tan())),
            Some(deg) => Err(ctx.err(
                child(persp, name).unwrap_or(persp),
                format!("{deg}° is not a field of view between 0° and 180°"),
            )),
            None => Ok(None),
        }
    };
    let (tx, ty) = (tan_half("xfov")?, tan_half("yfov")?);
    let aspect = match ctx.child_scalar(persp, "aspect_ratio")? {
        Some(a) if a > 0.0 => Some(a),
        // SketchUp always writes 0, and Assimp where its source had none: "not given".
        Some(0.0) => {
            let node = child(persp, "aspect_ratio").unwrap_or(persp);
            ctx.warn(node, "aspect ratio 0 read as not given");
            None
        }
        Some(a) => {
            let node = child(persp, "aspect_ratio").unwrap_or(persp);
            return Err(ctx.err(node, format!("aspect ratio {a} is not positive")));
        }
        None => None,
    };
    Ok(match (tx, ty, aspect) {
        (Some(tx), None, Some(a)) => (Some(tx), Some(tx / a)),
        (None, Some(ty), Some(a)) => (Some(ty * a), Some(ty)),
        (None, None, _) => {
            ctx.warn(persp, "no xfov or yfov; using the default field of view");
            let d = CameraDesc::default();
            (d.tan_half_x, d.tan_half_y)
        }
        (tx, ty, _) => (tx, ty),
    })
}
