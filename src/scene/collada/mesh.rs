//! `<mesh>` reading (spec §3): sources, `<vertices>`, and the polygon
//! primitives, fan-triangulated, in the geometry's local frame.

use super::xml::{child, children, Ctx};
use super::LoadError;
use glam::{Vec2, Vec3};
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

/// One TEXCOORD set of a mesh: per triangle, its corners' indices into
/// `LocalMesh::uvs` (`None` for triangles of primitives without this set).
#[derive(Clone, Debug)]
pub(crate) struct UvSet {
    /// The inputs' `set` attribute (0 when absent).
    pub set: u32,
    pub corners: Vec<Option<[u32; 3]>>,
}

/// One `<geometry>`'s mesh before instancing.
#[derive(Clone, Default, Debug)]
pub(crate) struct LocalMesh<'a> {
    pub positions: Vec<Vec3>,
    /// Base and count in `positions` of the `<vertices>` POSITION source: the
    /// vertices a skin's weights index (`None` if no primitive reads them).
    pub vertices: Option<(u32, u32)>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub triangles: Vec<LocalTriangle>,
    pub uv_sets: Vec<UvSet>,
    /// Material symbol of each primitive element, in file order.
    pub symbols: Vec<Option<&'a str>>,
}

impl LocalMesh<'_> {
    /// The texture coordinates set `set` gives triangle `i`, else those of the first set.
    pub fn triangle_uvs(&self, set: Option<u32>, i: usize) -> Option<[u32; 3]> {
        let chosen = set
            .and_then(|s| self.uv_sets.iter().find(|u| u.set == s))
            .or(self.uv_sets.first())?;
        chosen.corners.get(i).copied().flatten()
    }

    fn push_triangle(&mut self, t: LocalTriangle, uvs: &[(u32, [u32; 3])]) {
        let i = self.triangles.len();
        self.triangles.push(t);
        for &(set, _) in uvs {
            if !self.uv_sets.iter().any(|u| u.set == set) {
                self.uv_sets.push(UvSet {
                    set,
                    corners: Vec::new(),
                });
            }
        }
        for u in &mut self.uv_sets {
            u.corners.resize(i, None);
            u.corners
                .push(uvs.iter().find(|(s, _)| *s == u.set).map(|&(_, c)| c));
        }
    }
}

/// Where each `<source>` already read landed in the local position/normal/uv lists.
#[derive(Default)]
struct SourceBases {
    positions: HashMap<roxmltree::NodeId, (u32, u32)>,
    normals: HashMap<roxmltree::NodeId, (u32, u32)>,
    uvs: HashMap<roxmltree::NodeId, (u32, u32)>,
}

/// How one corner of a primitive is read from its `<p>` indices.
struct Layout {
    stride: usize,
    vertex_offset: usize,
    /// Base and count of the positions in `LocalMesh::positions`.
    positions: (u32, u32),
    /// Offset in the corner, base and count of the normals.
    normals: Option<(usize, (u32, u32))>,
    /// Set, offset in the corner, base and count of each TEXCOORD input.
    uvs: Vec<(u32, usize, (u32, u32))>,
}

/// The primitive elements that make triangles.
const SURFACES: [&str; 5] = ["triangles", "polylist", "polygons", "tristrips", "trifans"];

pub(crate) fn parse_mesh<'a, 'i>(
    ctx: &mut Ctx<'a, 'i>,
    mesh_node: Node<'a, 'i>,
) -> Result<LocalMesh<'a>, LoadError> {
    let mut mesh = LocalMesh::default();
    let mut bases = SourceBases::default();
    for prim in mesh_node.children().filter(Node::is_element) {
        let kind = prim.tag_name().name();
        if matches!(kind, "lines" | "linestrips") {
            ctx.warn_once(
                "lines",
                prim,
                "<lines> and <linestrips> have no area and are not rendered; skipped",
            );
            continue;
        }
        if !SURFACES.contains(&kind) {
            continue;
        }
        let layout = read_layout(ctx, prim, &mut mesh, &mut bases)?;
        let group = mesh.symbols.len() as u32;
        mesh.symbols.push(prim.attribute("material"));
        let mut out = Emitter {
            layout: &layout,
            group,
            mesh: &mut mesh,
            bad_uv: false,
            short_faces: false,
        };
        match kind {
            "triangles" => read_triangles(ctx, prim, &mut out)?,
            "polylist" => read_polylist(ctx, prim, &mut out)?,
            "polygons" => read_polygons(ctx, prim, &mut out)?,
            _ => read_strips(ctx, prim, kind == "tristrips", &mut out)?,
        }
        if kind == "triangles" && children(prim, "p").nth(1).is_some() {
            let msg = "several <p> in a <triangles> (COLLADA allows one); all are read";
            ctx.warn_once("several p", prim, msg);
        }
        if out.short_faces {
            let msg = "a face of fewer than 3 corners makes no triangle; skipped";
            ctx.warn_once("short face", prim, msg);
        }
        if out.bad_uv {
            ctx.warn(
                prim,
                "a TEXCOORD index is out of range; those triangles have no texture coordinates",
            );
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
    let mut stride = 0;
    let mut vertex = None;
    let mut normal = None;
    let mut texcoords = Vec::new();
    for input in children(prim, "input") {
        let offset = input_offset(ctx, input)?;
        stride = stride.max(offset + 1);
        match input.attribute("semantic") {
            Some("VERTEX") if vertex.is_none() => vertex = Some((input, offset)),
            Some("NORMAL") if normal.is_none() => normal = Some((input, offset)),
            Some("TEXCOORD") => texcoords.push((input, offset)),
            Some("COLOR") => warn_vertex_colours(ctx, input),
            _ => {}
        }
    }
    let (vinput, vertex_offset) = vertex.ok_or_else(|| ctx.err(prim, "no VERTEX input"))?;
    let (pos_source, vertex_normals, via_vertices) = match direct_source(ctx, vinput) {
        Some(source) => {
            let msg = "VERTEX names a <source>, not a <vertices>; read as the positions";
            ctx.warn_once("vertex source", vinput, msg);
            (source, None, false)
        }
        None => {
            let (source, normals) = vertex_inputs(ctx, vinput, vertex_offset, &mut texcoords)?;
            (source, normals, true)
        }
    };
    let positions = load_source(ctx, pos_source, &mut mesh.positions, &mut bases.positions)?;
    if via_vertices {
        mesh.vertices.get_or_insert(positions);
    }
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
    let uvs = read_texcoords(ctx, &texcoords, mesh, bases);
    Ok(Layout {
        stride,
        vertex_offset,
        positions,
        normals,
        uvs,
    })
}

/// A shared `<input>`'s `offset` (in `<p>`, or in a skin's `<v>`).
pub(crate) fn input_offset(ctx: &Ctx, input: Node) -> Result<usize, LoadError> {
    let offset = ctx
        .uint_attr(input, "offset")?
        .ok_or_else(|| ctx.err(input, "missing attribute offset"))?;
    if offset > MAX_OFFSET {
        return Err(ctx.err(input, format!("offset {offset} is too large")));
    }
    Ok(offset as usize)
}

/// The POSITION source and NORMAL input of the `<vertices>` that VERTEX input
/// `vinput` names; its TEXCOORD inputs join `texcoords` at VERTEX's offset.
fn vertex_inputs<'a, 'i>(
    ctx: &mut Ctx<'a, 'i>,
    vinput: Node<'a, 'i>,
    vertex_offset: usize,
    texcoords: &mut Vec<(Node<'a, 'i>, usize)>,
) -> Result<(Node<'a, 'i>, Option<Node<'a, 'i>>), LoadError> {
    let vertices = ctx.resolve(vinput, "source", "vertices")?;
    let mut pos_input = None;
    let mut normals = None;
    for input in children(vertices, "input") {
        match input.attribute("semantic") {
            Some("POSITION") if pos_input.is_none() => pos_input = Some(input),
            Some("NORMAL") if normals.is_none() => normals = Some(input),
            // A TEXCOORD inside <vertices> shares VERTEX's index.
            Some("TEXCOORD") => texcoords.push((input, vertex_offset)),
            Some("COLOR") => warn_vertex_colours(ctx, input),
            _ => {}
        }
    }
    let pos_input = pos_input.ok_or_else(|| ctx.err(vertices, "no POSITION input"))?;
    Ok((ctx.resolve(pos_input, "source", "source")?, normals))
}

/// MeshLab and photogrammetry tools colour vertices; ember's materials do not read it.
fn warn_vertex_colours(ctx: &mut Ctx, input: Node) {
    let msg = "vertex colours (COLOR) are not rendered; ignored";
    ctx.warn_once("vertex colours", input, msg);
}

/// The `<source>` a VERTEX input names directly, where COLLADA wants a `<vertices>`.
fn direct_source<'a, 'i>(ctx: &Ctx<'a, 'i>, vinput: Node<'a, 'i>) -> Option<Node<'a, 'i>> {
    let id = vinput.attribute("source")?.strip_prefix('#')?;
    ctx.by_id(id).filter(|n| n.has_tag_name("source"))
}

/// The TEXCOORD inputs' sets. Texture coordinates only matter to textures, so a
/// source that cannot be read loses them with a warning rather than the mesh.
fn read_texcoords(
    ctx: &mut Ctx,
    inputs: &[(Node, usize)],
    mesh: &mut LocalMesh,
    bases: &mut SourceBases,
) -> Vec<(u32, usize, (u32, u32))> {
    let mut out = Vec::new();
    for (k, &(input, offset)) in inputs.iter().enumerate() {
        let set = match ctx.uint_attr(input, "set") {
            Ok(Some(s)) => s.min(u32::MAX as u64) as u32,
            _ => k as u32,
        };
        if out.iter().any(|&(s, _, _)| s == set) {
            continue;
        }
        let range = ctx
            .resolve(input, "source", "source")
            .and_then(|src| load_uv_source(ctx, src, &mut mesh.uvs, &mut bases.uvs));
        match range {
            Ok(range) => out.push((set, offset, range)),
            Err(e) => {
                let why = e.to_string();
                let why = why.strip_prefix(&format!("{}: ", ctx.file)).unwrap_or(&why);
                ctx.warn(input, format!("texture coordinates ignored: {why}"));
            }
        }
    }
    out
}

/// Appends a `<source>`'s 3-vectors to `out` once (2-vectors get z = 0); returns
/// their base and count.
fn load_source(
    ctx: &Ctx,
    source: Node,
    out: &mut Vec<Vec3>,
    bases: &mut HashMap<roxmltree::NodeId, (u32, u32)>,
) -> Result<(u32, u32), LoadError> {
    let flat = accessor_params(source) == Some(2);
    load_source_as(ctx, source, out, bases, 3, |c| {
        // Two-component positions (2D meshes) lie in the z = 0 plane.
        Vec3::new(c[0], c[1], if flat || c.len() == 2 { 0.0 } else { c[2] })
    })
}

/// Appends a `<source>`'s texture coordinates (its first two components) to `out` once.
fn load_uv_source(
    ctx: &Ctx,
    source: Node,
    out: &mut Vec<Vec2>,
    bases: &mut HashMap<roxmltree::NodeId, (u32, u32)>,
) -> Result<(u32, u32), LoadError> {
    load_source_as(ctx, source, out, bases, 2, |c| Vec2::new(c[0], c[1]))
}

/// Appends a `<source>`'s elements (at least two components each; `default_stride`
/// without an accessor), made by `make`, to `out` once; returns their base and count.
fn load_source_as<T>(
    ctx: &Ctx,
    source: Node,
    out: &mut Vec<T>,
    bases: &mut HashMap<roxmltree::NodeId, (u32, u32)>,
    default_stride: u64,
    make: impl Fn(&[f32]) -> T,
) -> Result<(u32, u32), LoadError> {
    if let Some(&range) = bases.get(&source.id()) {
        return Ok(range);
    }
    let (values, stride, count) = source_values(ctx, source, 2, default_stride)?;
    let base = out.len();
    out.extend(values.chunks_exact(stride).take(count).map(make));
    let range = (base as u32, count as u32);
    bases.insert(source.id(), range);
    Ok(range)
}

/// How many `<param>`s a source's accessor names, if it names any.
fn accessor_params(source: Node) -> Option<usize> {
    let accessor = child(source, "technique_common").and_then(|t| child(t, "accessor"))?;
    let n = children(accessor, "param").count();
    (n > 0).then_some(n)
}

/// A `<source>`'s numbers, its accessor's stride (at least `dims`; `default_stride`
/// without an accessor) and element count.
pub(crate) fn source_values(
    ctx: &Ctx,
    source: Node,
    dims: u64,
    default_stride: u64,
) -> Result<(Vec<f32>, usize, usize), LoadError> {
    let array = child(source, "float_array").ok_or_else(|| ctx.err(source, "no <float_array>"))?;
    let values = float_array(ctx, array)?;
    let accessor = child(source, "technique_common").and_then(|t| child(t, "accessor"));
    if values.is_empty() {
        // An empty source (exporters write them for empty meshes) has no stride to check.
        return Ok((values, dims as usize, 0));
    }
    let stride = match accessor {
        Some(a) => ctx.uint_attr(a, "stride")?.unwrap_or(1),
        None => default_stride,
    };
    if stride < dims {
        let at = accessor.unwrap_or(source);
        return Err(ctx.err(
            at,
            format!("stride {stride} is too small for {dims}-component values"),
        ));
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
    if count > u32::MAX as u64 / 2 {
        return Err(ctx.err(source, "too many vertices"));
    }
    Ok((values, stride as usize, count as usize))
}

/// The numbers of a `<float_array>`. Fewer than its `count` is an error; more is read
/// with a warning (the accessors say which are used).
fn float_array(ctx: &Ctx, array: Node) -> Result<Vec<f32>, LoadError> {
    let values = ctx.numbers::<f32>(array)?;
    if let Some(count) = ctx.uint_attr(array, "count")? {
        if count > values.len() as u64 {
            return Err(ctx.err(
                array,
                format!("count is {count} but {} numbers are present", values.len()),
            ));
        }
        if count < values.len() as u64 {
            ctx.note(
                array,
                format!(
                    "count is {count} but {} numbers are present; the extra ones are not read",
                    values.len()
                ),
            );
            let mut values = values;
            values.truncate(count as usize);
            return Ok(values);
        }
    }
    Ok(values)
}

/// Where a primitive's triangles go: its layout, material group and mesh.
struct Emitter<'l, 'm, 'a> {
    layout: &'l Layout,
    group: u32,
    mesh: &'m mut LocalMesh<'a>,
    /// A TEXCOORD index was out of range (those triangles get no coordinates).
    bad_uv: bool,
    /// A face of fewer than three corners was skipped.
    short_faces: bool,
}

impl Emitter<'_, '_, '_> {
    /// Appends the triangle of corners `c` (each a slice of `stride` indices).
    fn triangle(
        &mut self,
        ctx: &Ctx,
        p: Node,
        face: usize,
        c: [&[u32]; 3],
    ) -> Result<(), LoadError> {
        let l = self.layout;
        let index = |corner: &[u32], offset: usize, (base, n): (u32, u32), what: &str| {
            let i = corner[offset];
            if i < n {
                Ok(base + i)
            } else {
                Err(ctx.err(
                    p,
                    format!("face {face}: {what} index {i} is out of range (only {n} available)"),
                ))
            }
        };
        let mut v = [0; 3];
        for k in 0..3 {
            v[k] = index(c[k], l.vertex_offset, l.positions, "position")?;
        }
        let n = match l.normals {
            Some((off, range)) => {
                let mut n = [0; 3];
                for k in 0..3 {
                    n[k] = index(c[k], off, range, "normal")?;
                }
                Some(n)
            }
            None => None,
        };
        let mut uvs = Vec::with_capacity(l.uvs.len());
        for &(set, off, (base, count)) in &l.uvs {
            let idx = c.map(|corner| corner[off]);
            if idx.iter().all(|&i| i < count) {
                uvs.push((set, idx.map(|i| base + i)));
            } else {
                self.bad_uv = true;
            }
        }
        let t = LocalTriangle {
            v,
            n,
            group: self.group,
        };
        self.mesh.push_triangle(t, &uvs);
        Ok(())
    }

    /// Triangulates one polygon from its corners' indices: a convex one as the fan
    /// `(c0, ci, ci+1)`, a concave one (SketchUp and CAD exporters write them) by ear
    /// clipping, so no triangle covers a notch. Both give `k − 2` triangles.
    fn polygon(
        &mut self,
        ctx: &Ctx,
        p: Node,
        face: usize,
        indices: &[u32],
    ) -> Result<(), LoadError> {
        let s = self.layout.stride;
        if indices.len() / s > 3 && is_concave(&self.mesh.positions, self.layout, indices) {
            let (corners, tris) =
                triangulate_with_holes(&self.mesh.positions, self.layout, &[indices]);
            for t in tris {
                self.triangle(ctx, p, face, t.map(|k| corners[k]))?;
            }
            return Ok(());
        }
        let corner = |k: usize| &indices[k * s..(k + 1) * s];
        for i in 1..indices.len() / s - 1 {
            self.triangle(ctx, p, face, [corner(0), corner(i), corner(i + 1)])?;
        }
        Ok(())
    }
}

/// `<triangles>`: COLLADA allows one `<p>`; some exporters write one per batch of
/// faces, so every `<p>` is read (the caller warns) and `count` covers them all.
fn read_triangles(ctx: &Ctx, prim: Node, out: &mut Emitter) -> Result<(), LoadError> {
    let per_face = 3 * out.layout.stride;
    let mut faces = 0;
    for p in children(prim, "p") {
        let indices = ctx.numbers::<u32>(p)?;
        if indices.len() % per_face != 0 {
            return Err(ctx.err(
                p,
                format!(
                    "{} indices is not a whole number of triangles ({per_face} per triangle)",
                    indices.len()
                ),
            ));
        }
        for corners in indices.chunks_exact(per_face) {
            out.polygon(ctx, p, faces, corners)?;
            faces += 1;
        }
    }
    check_count(ctx, prim, faces)
}

fn read_polylist(ctx: &Ctx, prim: Node, out: &mut Emitter) -> Result<(), LoadError> {
    let stride = out.layout.stride;
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
    let needed = corners.saturating_mul(stride as u64);
    if needed != indices.len() as u64 {
        return Err(ctx.err(
            vc,
            format!(
                "vcount sums to {corners} corners × {stride} indices each = {needed}, but <p> has {} indices",
                indices.len()
            ),
        ));
    }
    let mut start = 0;
    for (face, &k) in vcounts.iter().enumerate() {
        let len = k as usize * stride;
        // Fewer than three corners make no triangle; exporters write such faces.
        if k >= 3 {
            out.polygon(ctx, p, face, &indices[start..start + len])?;
        } else {
            out.short_faces = true;
        }
        start += len;
    }
    Ok(())
}

/// The indices of one `<p>` (or `<h>`, or a strip's or fan's `<p>`): whole corners,
/// and `None` for fewer than three, which make no polygon.
fn polygon_indices(ctx: &Ctx, p: Node, stride: usize) -> Result<Option<Vec<u32>>, LoadError> {
    let indices = ctx.numbers::<u32>(p)?;
    if indices.len() % stride != 0 {
        return Err(ctx.err(
            p,
            format!(
                "{} indices is not a whole number of corners ({stride} per corner)",
                indices.len()
            ),
        ));
    }
    Ok((indices.len() >= 3 * stride).then_some(indices))
}

fn read_polygons(ctx: &Ctx, prim: Node, out: &mut Emitter) -> Result<(), LoadError> {
    let stride = out.layout.stride;
    let mut faces = 0;
    for (face, p) in prim
        .children()
        .filter(|c| c.is_element() && matches!(c.tag_name().name(), "p" | "ph"))
        .enumerate()
    {
        faces += 1;
        if p.tag_name().name() == "p" {
            match polygon_indices(ctx, p, stride)? {
                Some(indices) => out.polygon(ctx, p, face, &indices)?,
                None => out.short_faces = true,
            }
        } else {
            let outer = child(p, "p").ok_or_else(|| ctx.err(p, "<ph> without <p>"))?;
            let Some(outer_indices) = polygon_indices(ctx, outer, stride)? else {
                out.short_faces = true;
                continue;
            };
            let mut holes = Vec::new();
            for h in children(p, "h") {
                match polygon_indices(ctx, h, stride)? {
                    Some(hole) => holes.push(hole),
                    None => out.short_faces = true,
                }
            }
            let loops: Vec<&[u32]> = std::iter::once(outer_indices.as_slice())
                .chain(holes.iter().map(Vec::as_slice))
                .collect();
            let (corners, tris) = triangulate_with_holes(&out.mesh.positions, out.layout, &loops);
            for t in tris {
                out.triangle(ctx, outer, face, t.map(|k| corners[k]))?;
            }
        }
    }
    check_count(ctx, prim, faces)
}

/// `<tristrips>` and `<trifans>`: each `<p>` is one strip or fan. A strip's
/// triangle `k` is `(k, k+1, k+2)`, with corners 0 and 1 swapped on odd `k` so
/// every triangle keeps the strip's winding.
fn read_strips(ctx: &Ctx, prim: Node, strip: bool, out: &mut Emitter) -> Result<(), LoadError> {
    let stride = out.layout.stride;
    let mut faces = 0;
    for (face, p) in children(prim, "p").enumerate() {
        faces += 1;
        // Fewer than three corners make no triangle; exporters write such stubs.
        let Some(indices) = polygon_indices(ctx, p, stride)? else {
            out.short_faces = true;
            continue;
        };
        if !strip {
            out.polygon(ctx, p, face, &indices)?;
        } else {
            let corner = |k: usize| &indices[k * stride..(k + 1) * stride];
            for k in 0..indices.len() / stride - 2 {
                let c = if k % 2 == 0 {
                    [corner(k), corner(k + 1), corner(k + 2)]
                } else {
                    [corner(k + 1), corner(k), corner(k + 2)]
                };
                out.triangle(ctx, p, face, c)?;
            }
        }
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

/// Triangulates a polygon with holes (`loops[0]` the outline, the rest holes, each a
/// list of corners of `layout.stride` indices): each hole is bridged to the outline
/// by a segment from its rightmost corner (in the polygon's plane) to the nearest
/// visible outline corner, and the single loop that makes is ear-clipped. Returns
/// the corners (slices of `loops`) and the triangles as indices into them. Out-of-
/// range position indices are left to `Emitter::triangle` to report.
fn triangulate_with_holes<'l>(
    positions: &[Vec3],
    layout: &Layout,
    loops: &[&'l [u32]],
) -> (Vec<&'l [u32]>, Vec<[usize; 3]>) {
    let s = layout.stride;
    let (base, count) = layout.positions;
    let corners: Vec<Vec<&[u32]>> = loops.iter().map(|l| l.chunks_exact(s).collect()).collect();
    let pos = |c: &[u32]| {
        let i = c[layout.vertex_offset];
        if i < count {
            positions[(base + i) as usize]
        } else {
            Vec3::ZERO
        }
    };
    // Project onto the plane of the outline's Newell normal.
    let outline: Vec<Vec3> = corners[0].iter().map(|c| pos(c)).collect();
    let normal = newell_normal(&outline);
    let (ax, ay) = plane_axes(normal);
    let flat = |c: &[u32]| {
        let p = pos(c);
        Vec2::new(p.dot(ax), p.dot(ay))
    };
    // One loop of corner ids (index into `all`), holes spliced in.
    let mut all: Vec<&[u32]> = corners[0].clone();
    let mut ring: Vec<usize> = (0..all.len()).collect();
    let mut holes: Vec<(f32, Vec<usize>)> = corners[1..]
        .iter()
        .map(|h| {
            let ids: Vec<usize> = (all.len()..all.len() + h.len()).collect();
            all.extend(h.iter().copied());
            let max_x = ids.iter().map(|&k| flat(all[k]).x).fold(f32::MIN, f32::max);
            (max_x, ids)
        })
        .collect();
    // Holes run against the outline (COLLADA fixes neither orientation).
    let signed_area = |ids: &[usize]| -> f32 {
        (0..ids.len())
            .map(|k| cross2(flat(all[ids[k]]), flat(all[ids[(k + 1) % ids.len()]])))
            .sum()
    };
    let outline_area = signed_area(&ring);
    for (_, hole) in &mut holes {
        if signed_area(hole) * outline_area > 0.0 {
            hole.reverse();
        }
    }
    // Rightmost holes first, so later bridges do not cross earlier ones.
    holes.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (_, hole) in holes {
        let (h_at, _) = hole
            .iter()
            .enumerate()
            .max_by(|a, b| flat(all[*a.1]).x.total_cmp(&flat(all[*b.1]).x))
            .unwrap_or((0, &hole[0]));
        let hp = flat(all[hole[h_at]]);
        let visible = |k: usize| {
            let a = flat(all[ring[k]]);
            (0..ring.len()).all(|e| {
                let (p, q) = (flat(all[ring[e]]), flat(all[ring[(e + 1) % ring.len()]]));
                e == k || (e + 1) % ring.len() == k || !segments_cross(hp, a, p, q)
            })
        };
        let best = (0..ring.len())
            .filter(|&k| visible(k))
            .min_by(|&a, &b| {
                let da = (flat(all[ring[a]]) - hp).length_squared();
                let db = (flat(all[ring[b]]) - hp).length_squared();
                da.total_cmp(&db)
            })
            .unwrap_or(0);
        // ring[..=best], hole from h_at around to h_at, back to ring[best], rest.
        let mut spliced = ring[..=best].to_vec();
        spliced.extend((0..=hole.len()).map(|j| hole[(h_at + j) % hole.len()]));
        spliced.extend_from_slice(&ring[best..]);
        ring = spliced;
    }
    let flat_ring: Vec<Vec2> = ring.iter().map(|&k| flat(all[k])).collect();
    let tris = ear_clip(&flat_ring)
        .into_iter()
        .map(|t| t.map(|k| ring[k]))
        .collect();
    (all, tris)
}

/// Whether a polygon (corners of `layout.stride` indices) turns both ways in its plane.
fn is_concave(positions: &[Vec3], layout: &Layout, indices: &[u32]) -> bool {
    let (base, count) = layout.positions;
    let p: Vec<Vec3> = indices
        .chunks_exact(layout.stride)
        .map(|c| c[layout.vertex_offset])
        .map(|i| {
            if i < count {
                positions[(base + i) as usize]
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    let n = newell_normal(&p);
    let scale = p.iter().map(|v| v.abs().max_element()).fold(0.0, f32::max);
    (0..p.len()).any(|i| {
        let (a, b, c) = (p[i], p[(i + 1) % p.len()], p[(i + 2) % p.len()]);
        (b - a).cross(c - b).dot(n) < -1e-6 * scale * scale
    })
}

fn newell_normal(p: &[Vec3]) -> Vec3 {
    let mut n = Vec3::ZERO;
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        n += Vec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    n.normalize_or_zero()
}

/// Two axes spanning the plane of unit `n` such that `(ax, ay, n)` is right-handed.
fn plane_axes(n: Vec3) -> (Vec3, Vec3) {
    if n == Vec3::ZERO {
        return (Vec3::X, Vec3::Y);
    }
    let ax = n.any_orthonormal_vector();
    (ax, n.cross(ax))
}

fn cross2(a: Vec2, b: Vec2) -> f32 {
    a.x * b.y - a.y * b.x
}

/// Whether segments `ab` and `pq` cross at a point inside both.
fn segments_cross(a: Vec2, b: Vec2, p: Vec2, q: Vec2) -> bool {
    let d1 = cross2(b - a, p - a);
    let d2 = cross2(b - a, q - a);
    let d3 = cross2(q - p, a - p);
    let d4 = cross2(q - p, b - p);
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// Ear clipping of a simple (or bridged) counter-clockwise or clockwise polygon;
/// every polygon of `n` corners yields `n − 2` triangles (where no ear is found,
/// as for a degenerate polygon, the rest is fanned).
fn ear_clip(p: &[Vec2]) -> Vec<[usize; 3]> {
    let area: f32 = (0..p.len())
        .map(|i| cross2(p[i], p[(i + 1) % p.len()]))
        .sum();
    let orient = if area < 0.0 { -1.0 } else { 1.0 };
    let mut idx: Vec<usize> = (0..p.len()).collect();
    let mut out = Vec::with_capacity(p.len().saturating_sub(2));
    while idx.len() > 3 {
        let n = idx.len();
        let ear = (0..n).find(|&i| {
            let (a, b, c) = (idx[(i + n - 1) % n], idx[i], idx[(i + 1) % n]);
            let convex = orient * cross2(p[b] - p[a], p[c] - p[b]) > 0.0;
            convex
                && idx.iter().all(|&k| {
                    k == a
                        || k == b
                        || k == c
                        || p[k] == p[a]
                        || p[k] == p[b]
                        || p[k] == p[c]
                        || !inside_triangle(p[k], p[a], p[b], p[c], orient)
                })
        });
        let i = ear.unwrap_or(1);
        out.push([idx[(i + n - 1) % n], idx[i], idx[(i + 1) % n]]);
        idx.remove(i);
    }
    if idx.len() == 3 {
        out.push([idx[0], idx[1], idx[2]]);
    }
    out
}

fn inside_triangle(q: Vec2, a: Vec2, b: Vec2, c: Vec2, orient: f32) -> bool {
    orient * cross2(b - a, q - a) >= 0.0
        && orient * cross2(c - b, q - b) >= 0.0
        && orient * cross2(a - c, q - c) >= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ear_clip_of_a_concave_polygon_stays_inside() {
        // An L shape: fanning from corner 0 would cover the notch.
        let p = [(0., 0.), (2., 0.), (2., 1.), (1., 1.), (1., 2.), (0., 2.)]
            .map(|(x, y)| Vec2::new(x, y));
        let tris = ear_clip(&p);
        assert_eq!(tris.len(), 4);
        let area: f32 = tris
            .iter()
            .map(|t| cross2(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]) * 0.5)
            .sum();
        assert!((area - 3.0).abs() < 1e-6, "{area}");
        for t in &tris {
            assert!(cross2(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]) > 0.0, "{t:?}");
        }
    }
}
