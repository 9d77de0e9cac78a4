//! `<mesh>` reading (spec §3): sources, `<vertices>`, and the polygon
//! primitives, fan-triangulated, in the geometry's local frame.

use super::xml::{child, children, Ctx};
use super::LoadError;
use glam::Vec3;
use roxmltree::Node;
use std::collections::HashMap;

/// Largest accepted input offset; real files use a handful.
const MAX_OFFSET: u64 = 255;

/// A triangle of a local mesh, indexing `LocalMesh::{positions, normals}`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LocalTriangle {
    pub v: [u32; 3],
    pub n: Option<[u32; 3]>,
    /// Index into `LocalMesh::symbols`: the primitive's material symbol.
    pub group: u32,
}

/// One `<geometry>`'s mesh before instancing.
#[derive(Default, Debug)]
pub(crate) struct LocalMesh<'a> {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<LocalTriangle>,
    /// Material symbol of each primitive element, in file order.
    pub symbols: Vec<Option<&'a str>>,
}

/// Where each `<source>` already read landed in the local position/normal lists.
#[derive(Default)]
struct SourceBases {
    positions: HashMap<roxmltree::NodeId, (u32, u32)>,
    normals: HashMap<roxmltree::NodeId, (u32, u32)>,
}

/// How one corner of a primitive is read from its `<p>` indices.
struct Layout {
    stride: usize,
    vertex_offset: usize,
    /// Base and count of the positions in `LocalMesh::positions`.
    positions: (u32, u32),
    /// Offset in the corner, base and count of the normals.
    normals: Option<(usize, (u32, u32))>,
}

pub(crate) fn parse_mesh<'a, 'i>(
    ctx: &mut Ctx<'a, 'i>,
    mesh_node: Node<'a, 'i>,
) -> Result<LocalMesh<'a>, LoadError> {
    let mut mesh = LocalMesh::default();
    let mut bases = SourceBases::default();
    for prim in mesh_node.children().filter(Node::is_element) {
        let kind = prim.tag_name().name();
        match kind {
            "triangles" | "polylist" | "polygons" => {}
            "lines" | "linestrips" | "tristrips" | "trifans" => {
                ctx.warn(prim, format!("<{kind}> is not supported; skipped"));
                continue;
            }
            _ => continue,
        }
        let layout = read_layout(ctx, prim, &mut mesh, &mut bases)?;
        let group = mesh.symbols.len() as u32;
        mesh.symbols.push(prim.attribute("material"));
        match kind {
            "triangles" => read_triangles(ctx, prim, &layout, group, &mut mesh)?,
            "polylist" => read_polylist(ctx, prim, &layout, group, &mut mesh)?,
            _ => read_polygons(ctx, prim, &layout, group, &mut mesh)?,
        }
    }
    Ok(mesh)
}

/// Reads the primitive's `<input>`s, loading the sources they name.
fn read_layout<'a, 'i>(
    ctx: &mut Ctx<'a, 'i>,
    prim: Node<'a, 'i>,
    mesh: &mut LocalMesh<'a>,
    bases: &mut SourceBases,
) -> Result<Layout, LoadError> {
    let mut stride = 0u64;
    let mut vertex = None;
    let mut normal = None;
    for input in children(prim, "input") {
        let offset = ctx
            .uint_attr(input, "offset")?
            .ok_or_else(|| ctx.err(input, "missing attribute offset"))?;
        if offset > MAX_OFFSET {
            return Err(ctx.err(input, format!("offset {offset} is too large")));
        }
        stride = stride.max(offset + 1);
        match input.attribute("semantic") {
            Some("VERTEX") if vertex.is_none() => vertex = Some((input, offset as usize)),
            Some("NORMAL") if normal.is_none() => normal = Some((input, offset as usize)),
            _ => {}
        }
    }
    let (vinput, vertex_offset) = vertex.ok_or_else(|| ctx.err(prim, "no VERTEX input"))?;
    let vertices = ctx.resolve(vinput, "source", "vertices")?;
    let mut pos_input = None;
    let mut vertex_normals = None;
    for input in children(vertices, "input") {
        match input.attribute("semantic") {
            Some("POSITION") if pos_input.is_none() => pos_input = Some(input),
            Some("NORMAL") if vertex_normals.is_none() => vertex_normals = Some(input),
            _ => {}
        }
    }
    let pos_input = pos_input.ok_or_else(|| ctx.err(vertices, "no POSITION input"))?;
    let pos_source = ctx.resolve(pos_input, "source", "source")?;
    let positions = load_source(ctx, pos_source, &mut mesh.positions, &mut bases.positions)?;
    // A NORMAL input of the primitive wins over one inside <vertices>, which shares VERTEX's index.
    let normals = match (normal, vertex_normals) {
        (Some((input, offset)), _) => Some((offset, input)),
        (None, Some(input)) => Some((vertex_offset, input)),
        (None, None) => None,
    };
    let normals = match normals {
        Some((offset, input)) => {
            let src = ctx.resolve(input, "source", "source")?;
            let range = load_source(ctx, src, &mut mesh.normals, &mut bases.normals)?;
            Some((offset, range))
        }
        None => None,
    };
    Ok(Layout {
        stride: stride as usize,
        vertex_offset,
        positions,
        normals,
    })
}

/// Appends a `<source>`'s 3-vectors to `out` once; returns their base and count.
fn load_source(
    ctx: &Ctx,
    source: Node,
    out: &mut Vec<Vec3>,
    bases: &mut HashMap<roxmltree::NodeId, (u32, u32)>,
) -> Result<(u32, u32), LoadError> {
    if let Some(&range) = bases.get(&source.id()) {
        return Ok(range);
    }
    let array = child(source, "float_array").ok_or_else(|| ctx.err(source, "no <float_array>"))?;
    let values = float_array(ctx, array)?;
    let accessor = child(source, "technique_common").and_then(|t| child(t, "accessor"));
    let stride = match accessor {
        Some(a) => ctx.uint_attr(a, "stride")?.unwrap_or(1),
        None => 3,
    };
    if stride < 3 {
        let at = accessor.unwrap_or(source);
        return Err(ctx.err(at, format!("stride {stride} is too small for 3D vectors")));
    }
    let available = values.len() as u64 / stride;
    let count = match accessor
        .map(|a| ctx.uint_attr(a, "count"))
        .transpose()?
        .flatten()
    {
        Some(c) if c > available => {
            let msg = format!(
                "count {c} with stride {stride} needs {} numbers but the array has {}",
                c.saturating_mul(stride),
                values.len()
            );
            return Err(ctx.err(accessor.unwrap_or(source), msg));
        }
        Some(c) => c,
        None => available,
    };
    let base = out.len();
    if base as u64 + count > u32::MAX as u64 / 2 {
        return Err(ctx.err(source, "too many vertices"));
    }
    let stride = stride as usize;
    out.extend(
        values
            .chunks_exact(stride)
            .take(count as usize)
            .map(|c| Vec3::new(c[0], c[1], c[2])),
    );
    let range = (base as u32, count as u32);
    bases.insert(source.id(), range);
    Ok(range)
}

/// The numbers of a `<float_array>`, which must match its `count`.
fn float_array(ctx: &Ctx, array: Node) -> Result<Vec<f32>, LoadError> {
    let values = ctx.numbers::<f32>(array)?;
    if let Some(count) = ctx.uint_attr(array, "count")? {
        if count != values.len() as u64 {
            return Err(ctx.err(
                array,
                format!("count is {count} but {} numbers are present", values.len()),
            ));
        }
    }
    Ok(values)
}

fn read_triangles(
    ctx: &Ctx,
    prim: Node,
    layout: &Layout,
    group: u32,
    mesh: &mut LocalMesh,
) -> Result<(), LoadError> {
    let Some(p) = child(prim, "p") else {
        return Ok(()); // A primitive without <p> has no faces.
    };
    let indices = ctx.numbers::<u32>(p)?;
    let per_face = 3 * layout.stride;
    if indices.len() % per_face != 0 {
        return Err(ctx.err(
            p,
            format!(
                "{} indices is not a whole number of triangles ({per_face} per triangle)",
                indices.len()
            ),
        ));
    }
    check_count(ctx, prim, indices.len() / per_face)?;
    for (face, corners) in indices.chunks_exact(per_face).enumerate() {
        emit_polygon(ctx, p, face, corners, layout, group, mesh)?;
    }
    Ok(())
}

fn read_polylist(
    ctx: &Ctx,
    prim: Node,
    layout: &Layout,
    group: u32,
    mesh: &mut LocalMesh,
) -> Result<(), LoadError> {
    let vcount_node = child(prim, "vcount");
    let p = child(prim, "p");
    let (vcounts, indices) = match (vcount_node, p) {
        (Some(vc), Some(p)) => (ctx.numbers::<u32>(vc)?, ctx.numbers::<u32>(p)?),
        (None, None) => return Ok(()),
        (None, Some(_)) => return Err(ctx.err(prim, "<p> without <vcount>")),
        (Some(_), None) => return Err(ctx.err(prim, "<vcount> without <p>")),
    };
    let (vc, p) = (vcount_node.unwrap_or(prim), p.unwrap_or(prim));
    check_count(ctx, prim, vcounts.len())?;
    let corners: u64 = vcounts.iter().map(|&k| k as u64).sum();
    let needed = corners.saturating_mul(layout.stride as u64);
    if needed != indices.len() as u64 {
        return Err(ctx.err(
            vc,
            format!(
                "vcount sums to {corners} corners × {} indices each = {needed}, but <p> has {} indices",
                layout.stride,
                indices.len()
            ),
        ));
    }
    let mut start = 0;
    for (face, &k) in vcounts.iter().enumerate() {
        let len = k as usize * layout.stride;
        if k < 3 {
            return Err(ctx.err(
                vc,
                format!("entry {face} is {k}; a polygon needs at least 3 corners"),
            ));
        }
        emit_polygon(
            ctx,
            p,
            face,
            &indices[start..start + len],
            layout,
            group,
            mesh,
        )?;
        start += len;
    }
    Ok(())
}

fn read_polygons(
    ctx: &mut Ctx,
    prim: Node,
    layout: &Layout,
    group: u32,
    mesh: &mut LocalMesh,
) -> Result<(), LoadError> {
    if child(prim, "ph").is_some() {
        ctx.warn(
            prim,
            "polygons with holes (<ph>) are not supported; skipped",
        );
    }
    let mut faces = 0;
    for (face, p) in children(prim, "p").enumerate() {
        let indices = ctx.numbers::<u32>(p)?;
        if indices.len() % layout.stride != 0 || indices.len() < 3 * layout.stride {
            return Err(ctx.err(
                p,
                format!(
                    "{} indices do not form a polygon of 3 or more corners ({} per corner)",
                    indices.len(),
                    layout.stride
                ),
            ));
        }
        emit_polygon(ctx, p, face, &indices, layout, group, mesh)?;
        faces += 1;
    }
    check_count(ctx, prim, faces)
}

/// The primitive's `count` attribute, when present, must equal its face count.
fn check_count(ctx: &Ctx, prim: Node, faces: usize) -> Result<(), LoadError> {
    match ctx.uint_attr(prim, "count")? {
        Some(c) if c != faces as u64 => {
            Err(ctx.err(prim, format!("count is {c} but {faces} faces are present")))
        }
        _ => Ok(()),
    }
}

/// Fan-triangulates one polygon `(c0, ci, ci+1)` from its corners' indices.
fn emit_polygon(
    ctx: &Ctx,
    p: Node,
    face: usize,
    indices: &[u32],
    layout: &Layout,
    group: u32,
    mesh: &mut LocalMesh,
) -> Result<(), LoadError> {
    let corner = |c: usize, offset: usize, (base, n): (u32, u32), what: &str| {
        let i = indices[c * layout.stride + offset];
        if i < n {
            Ok(base + i)
        } else {
            Err(ctx.err(
                p,
                format!("face {face}: {what} index {i} is out of range (only {n} available)"),
            ))
        }
    };
    let k = indices.len() / layout.stride;
    let vertex = |c| corner(c, layout.vertex_offset, layout.positions, "position");
    let normal = |c, (off, range)| corner(c, off, range, "normal");
    for i in 1..k - 1 {
        let n = match layout.normals {
            Some(nl) => Some([normal(0, nl)?, normal(i, nl)?, normal(i + 1, nl)?]),
            None => None,
        };
        mesh.triangles.push(LocalTriangle {
            v: [vertex(0)?, vertex(i)?, vertex(i + 1)?],
            n,
            group,
        });
    }
    Ok(())
}
