//! `<camera>` → `CameraDesc` (spec §4): view direction and field of view only.

use super::transform::linear;
use super::xml::{child, path, Ctx};
use super::LoadError;
use crate::scene::CameraDesc;
use glam::{DMat4, DVec3};
use roxmltree::Node;

pub(crate) fn read_camera(ctx: &mut Ctx, camera: Node, w: &DMat4) -> Result<CameraDesc, LoadError> {
    let (forward, up) = orientation(ctx, camera, w)?;
    let (tan_half_x, tan_half_y) = field_of_view(ctx, camera)?;
    Ok(CameraDesc {
        forward,
        up,
        tan_half_x,
        tan_half_y,
    })
}

/// `F = normalize(W3·(0,0,−1))`; `U` = world +Y made orthogonal to `F`, or
/// `W3·(0,1,0)` when `F` is parallel to +Y.
fn orientation(ctx: &Ctx, camera: Node, w: &DMat4) -> Result<(glam::Vec3, glam::Vec3), LoadError> {
    let w3 = linear(w);
    let f = w3 * DVec3::NEG_Z;
    if !f.is_finite() || f.length_squared() == 0.0 {
        return Err(ctx.err(
            camera,
            "the camera node's transform gives no view direction",
        ));
    }
    let f = f.normalize();
    let up = orthogonal_part(DVec3::Y, f)
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
        ctx.warn(
            camera,
            "no <perspective> optics; using the default field of view",
        );
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
