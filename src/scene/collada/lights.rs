//! `<light>` → `Light` (spec §5).

use super::transform::{linear, point};
use super::xml::{child, extension_technique, Ctx};
use super::LoadError;
use crate::lights::{AreaLight, Light, SpotLight};
use crate::Color;
use glam::{DMat4, DVec3, Vec3};
use roxmltree::Node;

const TYPES: [&str; 5] = ["area", "point", "directional", "ambient", "spot"];

/// The light placed by world matrix `w`, or `None` (with a warning) for an
/// unsupported or degenerate one.
pub(crate) fn read_light(
    ctx: &mut Ctx,
    light: Node,
    w: &DMat4,
) -> Result<Option<Light>, LoadError> {
    let extension = extension_technique(light)
        .and_then(|t| t.first_element_child())
        .filter(|e| TYPES.contains(&e.tag_name().name()));
    let common = child(light, "technique_common").and_then(|t| t.first_element_child());
    let Some(kind) = extension.or(common) else {
        ctx.warn(light, "light has no type; skipped");
        return Ok(None);
    };
    let name = kind.tag_name().name();
    if !TYPES.contains(&name) {
        ctx.warn(kind, format!("{name} lights are not supported; skipped"));
        return Ok(None);
    }
    let mut c = Color::from(
        ctx.child_colour(kind, "color")?
            .ok_or_else(|| ctx.err(kind, "missing <color>"))?,
    );
    if ctx.light_watts && matches!(name, "point" | "spot") {
        // Blender's power P of a point or spot light is that of the whole sphere
        // (a spot masks a point light), so its intensity is P/4π W/sr.
        c *= 0.25 * std::f32::consts::FRAC_1_PI;
        let msg = "Blender 2.80 and later write a point or spot light's power in watts; \
                   read as intensity power/4π W/sr";
        ctx.warn_once("light watts", kind, msg);
    }
    let light = match name {
        "area" => return area(ctx, kind, w, c),
        "point" => Light::Point {
            position: finite(ctx, kind, point(w, DVec3::ZERO))?,
            intensity: c,
        },
        "spot" => {
            let axis = linear(w) * DVec3::NEG_Z;
            if axis.length_squared() == 0.0 {
                return Err(ctx.err(kind, "the node transform has no −Z direction"));
            }
            let angle = ctx.child_scalar(kind, "falloff_angle")?.unwrap_or(180.0);
            let exponent = falloff_exponent(ctx, kind)?;
            if angle <= 0.0 || exponent < 0.0 {
                let msg = format!("falloff_angle {angle} must be positive and falloff_exponent {exponent} not negative");
                return Err(ctx.err(kind, msg));
            }
            // The cone's full angle: 360° already covers every direction.
            if let Some(a) = child(kind, "falloff_angle").filter(|_| angle > 360.0) {
                let msg = format!(
                    "{angle} degrees is wider than the whole sphere (a full angle of 360); read as 360"
                );
                ctx.warn(a, msg);
            }
            Light::Spot(SpotLight::new(
                finite(ctx, kind, point(w, DVec3::ZERO))?,
                finite(ctx, kind, axis.normalize())?,
                c,
                angle,
                exponent,
            ))
        }
        "directional" => {
            let t = linear(w) * DVec3::NEG_Z;
            if t.length_squared() == 0.0 {
                return Err(ctx.err(kind, "the node transform has no −Z direction"));
            }
            Light::Directional {
                direction: finite(ctx, kind, t.normalize())?,
                irradiance: c,
            }
        }
        // The hemisphere is about world up whatever the node transform says.
        _ => Light::Ambient { radiance: c },
    };
    Ok(Some(light))
}

/// Rectangle `centre + s·ex + t·ey`, `s,t ∈ [−½,½]`, facing the node's local −Z.
fn area(ctx: &mut Ctx, kind: Node, w: &DMat4, c: Color) -> Result<Option<Light>, LoadError> {
    let w3 = linear(w);
    let centre = finite(ctx, kind, point(w, DVec3::ZERO))?;
    let ex = finite(ctx, kind, w3 * DVec3::X)?;
    let ey = finite(ctx, kind, w3 * DVec3::Y)?;
    let cross = ex.cross(ey);
    let area = cross.length();
    let usable = area.is_finite() && area > 0.0;
    if !usable {
        ctx.warn(kind, "area light has zero area; skipped");
        return Ok(None);
    }
    let plane_normal = cross / area;
    let local_neg_z = (w3 * DVec3::NEG_Z).as_vec3();
    // A −Z lying in the plane says nothing; then −(ex × ey), the local −Z of a rotation.
    let normal = if plane_normal.dot(local_neg_z) > 0.0 {
        plane_normal
    } else {
        -plane_normal
    };
    Ok(Some(Light::Area(AreaLight {
        centre,
        ex,
        ey,
        normal,
        radiance: c,
    })))
}

/// `<falloff_exponent>`, 0 if absent. Assimp writes `inf` for a cone whose inner and
/// outer angles are equal, a hard edge: read as 0, no falloff, with a warning.
fn falloff_exponent(ctx: &mut Ctx, kind: Node) -> Result<f32, LoadError> {
    let Some(e) = child(kind, "falloff_exponent") else {
        return Ok(0.0);
    };
    let word = e.text().unwrap_or("").trim();
    if word.parse::<f32>().is_ok_and(|v| v == f32::INFINITY) {
        ctx.warn(
            e,
            "an infinite falloff exponent (a hard-edged cone) read as 0",
        );
        return Ok(0.0);
    }
    ctx.leading::<1>(e).map(|[v]| v)
}

fn finite(ctx: &Ctx, node: Node, v: DVec3) -> Result<Vec3, LoadError> {
    let v = v.as_vec3();
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ctx.err(
            node,
            "the node transform gives a non-finite light position or axis",
        ))
    }
}
