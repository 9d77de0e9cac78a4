//! `<material>` → `<effect>` → `Material` (spec §6), plus what the common
//! profile adds for files from other tools: `<emission>`, a diffuse texture, and
//! warnings for what a Lambertian surface cannot show.

use super::xml::{child, children, extension_technique, path, Ctx};
use super::LoadError;
use crate::materials::Material;
use crate::texture::Wrap;
use crate::Color;
use roxmltree::Node;

/// Extension elements that define a material; the last one present wins.
const KINDS: [&str; 5] = ["emission", "mirror", "glass", "refraction", "microfacet"];

/// The common profile's shading models, in the order they are looked for.
const MODELS: [&str; 4] = ["phong", "lambert", "blinn", "constant"];

/// A material as read, with the diffuse texture it names, if any.
pub(crate) struct ReadMaterial<'a, 'i> {
    pub material: Material,
    pub texture: Option<TextureRef<'a, 'i>>,
}

/// A `<diffuse><texture>`: the image it samples, how, and through which coordinates.
#[derive(Clone, Copy)]
pub(crate) struct TextureRef<'a, 'i> {
    pub image: Node<'a, 'i>,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    /// The `texcoord` semantic a `<bind_vertex_input>` maps to a TEXCOORD set.
    pub texcoord: Option<&'a str>,
    /// The colour to use if the image cannot be read: the effect's diffuse `<color>`,
    /// else its `<ambient>` one (3ds Max, Maya and older Blender exporters write the
    /// base colour there when the diffuse is a texture).
    pub fallback: Option<Color>,
}

/// Reads the material a `<material>` element names through its effect.
pub(crate) fn read_material<'a, 'i>(
    ctx: &mut Ctx<'a, 'i>,
    material: Node<'a, 'i>,
) -> Result<ReadMaterial<'a, 'i>, LoadError> {
    let instance = child(material, "instance_effect")
        .ok_or_else(|| ctx.err(material, "no <instance_effect>"))?;
    let effect = ctx.resolve(instance, "url", "effect")?;
    let special = extension_technique(effect).and_then(|t| {
        t.children()
            .rfind(|c| c.is_element() && KINDS.contains(&c.tag_name().name()))
    });
    if let Some(node) = special {
        return Ok(ReadMaterial {
            material: read_special(ctx, node)?,
            texture: None,
        });
    }
    let Some(technique) = path(effect, &["profile_COMMON", "technique"]) else {
        return Ok(ReadMaterial {
            material: Material::default(),
            texture: None,
        });
    };
    let Some(model) = MODELS.iter().find_map(|m| child(technique, m)) else {
        return Ok(ReadMaterial {
            material: Material::default(),
            texture: None,
        });
    };
    let emitted = emission(ctx, model)?;
    if !ctx.course_file {
        warn_unrendered(ctx, effect, model);
    }
    let colour = diffuse_colour(ctx, effect, model)?;
    let fallback = match colour {
        Some(c) => Some(c),
        None => path(model, &["ambient", "color"])
            .and_then(|c| ctx.leading::<3>(c).ok().map(Color::from)),
    };
    let texture = path(model, &["diffuse", "texture"])
        .map(|t| texture_ref(ctx, effect, t, fallback))
        .transpose()?
        .flatten();
    let albedo = match (colour, texture) {
        (Some(c), _) => c,
        // A texture alone is the albedo: it multiplies white.
        (None, Some(_)) => Color::ONE,
        // <constant> is unlit: it shows its emission and reflects nothing.
        (None, None) if model.has_tag_name("constant") => Color::ZERO,
        (None, None) => Color::splat(0.5),
    };
    if let (Some(c), Some(at)) = (colour, child(model, "diffuse")) {
        warn_gain(ctx, at, c);
    }
    let material = Material::lambertian(albedo);
    Ok(ReadMaterial {
        // The front side emits, as the course's emission material does.
        material: emitted.map_or(material, |e| material.with_emission(e, false)),
        texture,
    })
}

/// `<diffuse><color>`, or the `<float4>` (or `<float3>`) of the `<newparam>` that
/// `<diffuse><param ref>` names, if given.
fn diffuse_colour(ctx: &mut Ctx, effect: Node, model: Node) -> Result<Option<Color>, LoadError> {
    if let Some(c) = path(model, &["diffuse", "color"]) {
        return ctx.colour(c).map(|c| Some(Color::from(c)));
    }
    let Some(param) = path(model, &["diffuse", "param"]) else {
        return Ok(None);
    };
    let sid = param.attribute("ref").unwrap_or("");
    let value =
        newparam(effect, sid).and_then(|p| child(p, "float4").or_else(|| child(p, "float3")));
    match value {
        Some(v) => ctx.colour(v).map(|c| Some(Color::from(c))),
        None => {
            let msg = format!(
                "ref=\"{}\" names no <newparam> holding a colour; the default colour is used",
                super::xml::clip(sid)
            );
            ctx.warn(param, msg);
            Ok(None)
        }
    }
}

/// A reflectance above 1 in some channel returns more light than arrives: legal,
/// but rarely meant (a colour written as 0–255, say), so it is said once.
fn warn_gain(ctx: &mut Ctx, node: Node, c: Color) {
    if c.max_element() > 1.0 {
        let msg = format!(
            "a reflectance of {} is above 1: the surface returns more light than it receives",
            c.max_element()
        );
        ctx.warn(node, msg);
    }
}

/// `<emission><color>` when it is not black.
fn emission(ctx: &mut Ctx, model: Node) -> Result<Option<Color>, LoadError> {
    let Some(e) = child(model, "emission") else {
        return Ok(None);
    };
    if child(e, "texture").is_some() {
        ctx.warn(e, "an emission texture is not supported; ignored");
    }
    let c = child(e, "color")
        .map(|c| ctx.colour(c).map(Color::from))
        .transpose()?;
    Ok(c.filter(|c| c.max_element() > 0.0))
}

/// One warning per material listing what a Lambertian surface cannot show:
/// a specular highlight, reflection, transparency, bump and other texture maps.
fn warn_unrendered(ctx: &mut Ctx, effect: Node, model: Node) {
    let mut lost = Vec::new();
    let colour = |name: &str| match path(model, &[name, "color"]) {
        Some(c) => ctx
            .leading::<3>(c)
            .is_ok_and(|c| c.iter().any(|&v| v > 0.0)),
        None => path(model, &[name, "texture"]).is_some(),
    };
    if matches!(model.tag_name().name(), "phong" | "blinn") && colour("specular") {
        lost.push("specular colour and shininess");
    }
    if colour("reflective") && param_float(ctx, model, "reflectivity").unwrap_or(1.0) > 0.0 {
        lost.push("reflection");
    }
    if transparent(ctx, model) {
        lost.push("transparency");
    }
    let bump = effect
        .descendants()
        .any(|n| n.has_tag_name("bump") || n.has_tag_name("normalmap"));
    if bump {
        lost.push("bump map");
    }
    if lost.is_empty() {
        return;
    }
    let msg = format!(
        "{} not rendered; the surface is Lambertian (ember has no Phong lobe)",
        lost.join(", ")
    );
    ctx.warn(model, msg);
}

/// Whether the effect lets light through: with `opaque="A_ONE"` (the default), an
/// alpha times `<transparency>` below 1; with `RGB_ZERO`, a colour that is not black.
fn transparent(ctx: &Ctx, model: Node) -> bool {
    let Some(t) = child(model, "transparent") else {
        return false;
    };
    let amount = param_float(ctx, model, "transparency").unwrap_or(1.0);
    let rgb_zero = t.attribute("opaque") == Some("RGB_ZERO");
    match (child(t, "color"), rgb_zero) {
        (Some(c), false) => {
            let alpha = ctx.leading::<4>(c).map_or(1.0, |c| c[3]);
            alpha * amount < 0.999
        }
        (Some(c), true) => {
            let rgb = ctx.leading::<3>(c).unwrap_or([0.0; 3]);
            rgb.iter().any(|&v| v * amount > 0.001)
        }
        (None, _) => child(t, "texture").is_some(),
    }
}

/// A `<float>` parameter of the shading model (`<transparency><float>0.5</float>`),
/// if present and readable: it only decides a warning, so an odd one is passed over.
fn param_float(ctx: &Ctx, model: Node, name: &str) -> Option<f32> {
    let p = child(model, name)?;
    let f = child(p, "float")?;
    ctx.leading::<1>(f).ok().map(|[v]| v)
}

/// Resolves `<texture texture="X">`: `X` is a `<newparam>` `<sampler2D>` (COLLADA
/// 1.4: its `<source>` a `<surface>` newparam whose `<init_from>` names the image;
/// 1.5: its `<instance_image>`), or, as some exporters write, an image's id.
fn texture_ref<'a, 'i>(
    ctx: &mut Ctx<'a, 'i>,
    effect: Node<'a, 'i>,
    tex: Node<'a, 'i>,
    fallback: Option<Color>,
) -> Result<Option<TextureRef<'a, 'i>>, LoadError> {
    let name = tex.attribute("texture").unwrap_or("");
    let sampler = newparam(effect, name).and_then(|p| child(p, "sampler2D"));
    let image = match sampler {
        Some(s) => sampler_image(ctx, effect, s),
        None => ctx.image_by_id(name),
    };
    let Some(image) = image else {
        ctx.warn(
            tex,
            format!(
                "texture=\"{}\" names no sampler or image; the texture is ignored",
                super::xml::clip(name)
            ),
        );
        return Ok(None);
    };
    let wrap = |axis: &str| {
        let text = sampler
            .and_then(|s| child(s, axis))
            .and_then(|w| w.text())
            .map(str::trim);
        match text {
            Some("MIRROR") => Wrap::Mirror,
            Some("CLAMP" | "BORDER" | "NONE" | "MIRROR_ONCE") => Wrap::Clamp,
            _ => Wrap::Repeat,
        }
    };
    Ok(Some(TextureRef {
        image,
        wrap_s: wrap("wrap_s"),
        wrap_t: wrap("wrap_t"),
        texcoord: tex.attribute("texcoord"),
        fallback,
    }))
}

/// The `<newparam>` of `effect` whose sid is `sid`.
fn newparam<'a, 'i>(effect: Node<'a, 'i>, sid: &str) -> Option<Node<'a, 'i>> {
    effect
        .descendants()
        .find(|n| n.has_tag_name("newparam") && n.attribute("sid") == Some(sid))
}

fn sampler_image<'a, 'i>(
    ctx: &Ctx<'a, 'i>,
    effect: Node<'a, 'i>,
    sampler: Node<'a, 'i>,
) -> Option<Node<'a, 'i>> {
    if let Some(inst) = child(sampler, "instance_image") {
        return ctx.resolve_if_present(inst, "url", "image").ok().flatten();
    }
    let source = child(sampler, "source")?.text()?.trim();
    let surface = newparam(effect, source).and_then(|p| child(p, "surface"));
    let id = match surface {
        Some(s) => children(s, "init_from").next()?.text()?.trim(),
        // Some exporters name the image directly in <source>.
        None => source,
    };
    ctx.image_by_id(id)
}

/// One of the CGL extension materials. Missing parameters take the
/// defaults below, with a warning, so a sparse file still renders.
fn read_special<'a, 'i>(ctx: &mut Ctx<'a, 'i>, node: Node<'a, 'i>) -> Result<Material, LoadError> {
    let mut p = Params { ctx, node };
    let m = match node.tag_name().name() {
        "emission" => Material::emitter(p.rgb("radiance", 1.0)?),
        "mirror" => Material::mirror(p.reflectance("reflectance")?),
        "glass" => {
            p.require_smooth()?;
            let ior = p.positive("ior", 1.5)?;
            let r = p.reflectance("reflectance")?;
            Material::glass(ior, r, p.reflectance("transmittance")?)
        }
        "refraction" => {
            p.require_smooth()?;
            let ior = p.positive("ior", 1.5)?;
            Material::refraction(ior, p.reflectance("transmittance")?)
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
        match self.ctx.child_colour(self.node, name)? {
            Some(c) => Ok(Color::from(c)),
            None => {
                let msg = format!("missing <{name}>; using {default}");
                self.ctx.warn(self.node, msg);
                Ok(Color::splat(default))
            }
        }
    }

    /// A reflectance or transmittance (default 1), warned above 1.
    fn reflectance(&mut self, name: &str) -> Result<Color, LoadError> {
        let c = self.rgb(name, 1.0)?;
        if let Some(at) = child(self.node, name) {
            warn_gain(self.ctx, at, c);
        }
        Ok(c)
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
