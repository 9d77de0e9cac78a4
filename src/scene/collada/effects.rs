//! `<material>` → `<effect>` → `Material` (spec §6).

use super::xml::{child, extension_technique, path, Ctx};
use super::LoadError;
use crate::materials::Material;
use crate::Color;
use roxmltree::Node;

/// Extension elements that define a material; the last one present wins.
const KINDS: [&str; 5] = ["emission", "mirror", "glass", "refraction", "microfacet"];

/// Reads the material a `<material>` element names through its effect.
pub(crate) fn read_material<'a, 'i>(
    ctx: &mut Ctx<'a, 'i>,
    material: Node<'a, 'i>,
) -> Result<Material, LoadError> {
    let instance = child(material, "instance_effect")
        .ok_or_else(|| ctx.err(material, "no <instance_effect>"))?;
    let effect = ctx.resolve(instance, "url", "effect")?;
    let special = extension_technique(effect).and_then(|t| {
        t.children()
            .rfind(|c| c.is_element() && KINDS.contains(&c.tag_name().name()))
    });
    match special {
        Some(node) => read_special(ctx, node),
        None => Ok(Material::lambertian(diffuse_colour(ctx, effect)?)),
    }
}

/// `profile_COMMON/technique/{phong|lambert|blinn}/diffuse/color`, else 0.5 grey.
fn diffuse_colour(ctx: &Ctx, effect: Node) -> Result<Color, LoadError> {
    let Some(technique) = path(effect, &["profile_COMMON", "technique"]) else {
        return Ok(Color::splat(0.5));
    };
    let colour = ["phong", "lambert", "blinn"]
        .iter()
        .find_map(|model| path(technique, &[model, "diffuse", "color"]));
    match colour {
        Some(c) => Ok(Color::from(ctx.leading::<3>(c)?)),
        None => Ok(Color::splat(0.5)),
    }
}

/// One of the CGL extension materials. Missing parameters take the
/// defaults below, with a warning, so a sparse file still renders.
fn read_special<'a, 'i>(ctx: &mut Ctx<'a, 'i>, node: Node<'a, 'i>) -> Result<Material, LoadError> {
    let mut p = Params { ctx, node };
    let m = match node.tag_name().name() {
        "emission" => Material::emitter(p.rgb("radiance", 1.0)?),
        "mirror" => Material::mirror(p.rgb("reflectance", 1.0)?),
        "glass" => {
            p.require_smooth()?;
            let ior = p.positive("ior", 1.5)?;
            let r = p.rgb("reflectance", 1.0)?;
            Material::glass(ior, r, p.rgb("transmittance", 1.0)?)
        }
        "refraction" => {
            p.require_smooth()?;
            let ior = p.positive("ior", 1.5)?;
            Material::refraction(ior, p.rgb("transmittance", 1.0)?)
        }
        _ => {
            let alpha = p.positive("alpha", 0.5)?;
            let eta = p.rgb("eta", 1.0)?;
            Material::microfacet(alpha, eta, p.rgb("k", 0.0)?)
        }
    };
    Ok(m)
}

/// Parameter reader for one extension material element.
struct Params<'c, 'a, 'i> {
    ctx: &'c mut Ctx<'a, 'i>,
    node: Node<'a, 'i>,
}

impl Params<'_, '_, '_> {
    fn rgb(&mut self, name: &str, default: f32) -> Result<Color, LoadError> {
        match self.ctx.child_rgb(self.node, name)? {
            Some(c) => Ok(Color::from(c)),
            None => {
                let msg = format!("missing <{name}>; using {default}");
                self.ctx.warn(self.node, msg);
                Ok(Color::splat(default))
            }
        }
    }

    fn positive(&mut self, name: &str, default: f32) -> Result<f32, LoadError> {
        match self.ctx.child_scalar(self.node, name)? {
            Some(v) if v > 0.0 => Ok(v),
            Some(v) => Err(self
                .ctx
                .err(self.node, format!("<{name}> is {v}; it must be positive"))),
            None => {
                let msg = format!("missing <{name}>; using {default}");
                self.ctx.warn(self.node, msg);
                Ok(default)
            }
        }
    }

    /// Only smooth dielectrics are supported (spec §6); rough ones render smooth.
    fn require_smooth(&mut self) -> Result<(), LoadError> {
        if let Some(r) = self.ctx.child_scalar(self.node, "roughness")? {
            if r != 0.0 {
                let msg = format!("roughness {r} is not supported; rendered as 0");
                self.ctx.warn(self.node, msg);
            }
        }
        Ok(())
    }
}
