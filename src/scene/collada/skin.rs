//! `<skin>` reading: COLLADA 1.4.1's linear-blend skinning equation, evaluated at
//! the pose the visual scene gives the joints (animation is not read):
//! `v' = Σ_i w_i · J_i · IB_i · BSM · v`, with `J_i` the joint node's world matrix,
//! `IB_i` its inverse bind matrix and `BSM` the bind shape matrix. Exporters
//! disagree on what the bind matrices are relative to (Blender: the world at rest;
//! Assimp: the mesh node), and the equation places both where their tools show them.

use super::mesh::{input_offset, source_values, LocalMesh};
use super::transform::{bind_shape_matrix, node_world, normal_matrix, point};
use super::xml::{child, children, clip, Ctx};
use super::LoadError;
use glam::{DMat4, Vec3};
use roxmltree::Node;
use std::collections::HashMap;

/// Joint index in `<v>` that stands for the bind shape itself (`J·IB` = identity).
const BIND_SHAPE_JOINT: i64 = -1;
/// How far a vertex's weights may sum from 1 before they are normalised (with a warning).
const WEIGHT_SUM_TOLERANCE: f64 = 1e-3;

/// Whether a skin says how its joints move its vertices; without `<joints>` and
/// `<vertex_weights>` the mesh can only stay at its bind shape.
pub(crate) fn has_joints(skin: Node) -> bool {
    child(skin, "joints").is_some() && child(skin, "vertex_weights").is_some()
}

/// The skin's `<bind_shape_matrix>`, the identity when absent.
pub(crate) fn bind_shape(ctx: &Ctx, skin: Node) -> Result<DMat4, LoadError> {
    child(skin, "bind_shape_matrix").map_or(Ok(DMat4::IDENTITY), |m| bind_shape_matrix(ctx, m))
}

/// Each of the `count` source vertices' skinning matrix `Σ w_i·J_i·IB_i·BSM`, with
/// joints found under the instance's `<skeleton>` nodes (under `scene` without any).
pub(crate) fn vertex_matrices<'a, 'i>(
    ctx: &mut Ctx<'a, 'i>,
    skin: Node<'a, 'i>,
    inst: Node<'a, 'i>,
    scene: Node<'a, 'i>,
    count: usize,
) -> Result<Vec<DMat4>, LoadError> {
    let bsm = bind_shape(ctx, skin)?;
    let (Some(joints), Some(weights)) = (child(skin, "joints"), child(skin, "vertex_weights"))
    else {
        return Ok(vec![bsm; count]);
    };
    let scope = skeleton_roots(ctx, inst, scene);
    let nodes = joint_nodes(ctx, joints, &scope)?;
    let inverse_binds = inverse_binds(ctx, joints, nodes.len())?;
    let mut poses = Vec::with_capacity(nodes.len());
    for (node, ib) in nodes.into_iter().zip(inverse_binds) {
        poses.push(node_world(ctx, node)? * ib);
    }
    let blended = blend(ctx, weights, &poses, count)?;
    Ok(blended.into_iter().map(|m| m * bsm).collect())
}

/// `mesh` with each vertex of its `<vertices>` moved by its matrix and each corner
/// normal turned by its vertex's matrix. A normal that vertices of different weights
/// share becomes one normal per vertex. Positions from other sources stay as read.
pub(crate) fn posed<'a>(mesh: &LocalMesh<'a>, matrices: &[DMat4]) -> LocalMesh<'a> {
    let (base, count) = mesh.vertices.unwrap_or((0, 0));
    let matrix = |v: u32| {
        v.checked_sub(base)
            .filter(|&k| k < count)
            .and_then(|k| matrices.get(k as usize))
    };
    let mut out = mesh.clone();
    for (i, p) in out.positions.iter_mut().enumerate() {
        if let Some(m) = matrix(i as u32) {
            *p = point(m, p.as_dvec3()).as_vec3();
        }
    }
    let mut normals = Vec::new();
    let mut turned = HashMap::new();
    for t in &mut out.triangles {
        let Some(n) = &mut t.n else { continue };
        for (n, &v) in n.iter_mut().zip(&t.v) {
            *n = *turned.entry((*n, v)).or_insert_with(|| {
                let read = mesh.normals[*n as usize];
                normals.push(matrix(v).map_or(read, |m| turn(m, read)));
                (normals.len() - 1) as u32
            });
        }
    }
    out.normals = normals;
    out
}

/// A normal under `m`, normalised in f64 (the cofactor matrix grows with `m`'s scale).
fn turn(m: &DMat4, n: Vec3) -> Vec3 {
    (normal_matrix(m) * n.as_dvec3())
        .normalize_or_zero()
        .as_vec3()
}

/// Where a skin's joints are looked for, and how messages say so.
struct Scope<'a, 'i> {
    roots: Vec<Node<'a, 'i>>,
    label: &'static str,
}

/// The nodes the instance's `<skeleton>`s name; the whole `scene` when none does.
/// A `<skeleton>` naming nothing is only warned about: joints may still be found.
fn skeleton_roots<'a, 'i>(
    ctx: &mut Ctx<'a, 'i>,
    inst: Node<'a, 'i>,
    scene: Node<'a, 'i>,
) -> Scope<'a, 'i> {
    let mut roots = Vec::new();
    for s in children(inst, "skeleton") {
        let url = s.text().unwrap_or("").trim();
        let found = url.strip_prefix('#').and_then(|id| ctx.by_id(id));
        match found.filter(|n| n.has_tag_name("node")) {
            Some(n) => roots.push(n),
            None => ctx.warn(s, format!("\"{}\" names no <node>; ignored", clip(url))),
        }
    }
    if roots.is_empty() {
        let label = "in the visual scene";
        return Scope {
            roots: vec![scene],
            label,
        };
    }
    let label = "under the instance's <skeleton> nodes";
    Scope { roots, label }
}

/// The joint nodes `<joints>`' JOINT source names: an `IDREF_array` by id, a
/// `Name_array` by `sid`, else `name`, else `id` under the skeleton roots (Blender
/// names joints by sid, other exporters by name or id). A joint that matches no node
/// is an error: the vertices it moves would land somewhere wrong without a word.
fn joint_nodes<'a, 'i>(
    ctx: &Ctx<'a, 'i>,
    joints: Node<'a, 'i>,
    scope: &Scope<'a, 'i>,
) -> Result<Vec<Node<'a, 'i>>, LoadError> {
    let source = ctx.resolve(semantic_input(ctx, joints, "JOINT")?, "source", "source")?;
    if let Some(ids) = child(source, "IDREF_array") {
        return names(ctx, ids)?
            .into_iter()
            .map(|id| {
                let node = ctx.by_id(id).filter(|n| n.has_tag_name("node"));
                node.ok_or_else(|| {
                    ctx.err(ids, format!("joint \"{}\" is no <node>'s id", clip(id)))
                })
            })
            .collect();
    }
    let array = child(source, "Name_array")
        .ok_or_else(|| ctx.err(source, "no <Name_array> or <IDREF_array> of joints"))?;
    let index = JointIndex::new(&scope.roots);
    names(ctx, array)?
        .into_iter()
        .map(|name| {
            index.find(name).ok_or_else(|| {
                let msg = format!(
                    "joint \"{}\" matches no node's sid, name or id {}",
                    clip(name),
                    scope.label
                );
                ctx.err(array, msg)
            })
        })
        .collect()
}

/// The nodes under the skeleton roots by `sid`, `name` and `id` (first in document order).
struct JointIndex<'a, 'i> {
    by: [HashMap<&'a str, Node<'a, 'i>>; 3],
}

impl<'a, 'i> JointIndex<'a, 'i> {
    const KEYS: [&'static str; 3] = ["sid", "name", "id"];

    fn new(roots: &[Node<'a, 'i>]) -> Self {
        let mut by: [HashMap<&'a str, Node<'a, 'i>>; 3] = Default::default();
        let nodes = roots.iter().flat_map(|r| r.descendants());
        for n in nodes.filter(|n| n.has_tag_name("node")) {
            for (map, key) in by.iter_mut().zip(Self::KEYS) {
                if let Some(k) = n.attribute(key) {
                    map.entry(k).or_insert(n);
                }
            }
        }
        JointIndex { by }
    }

    fn find(&self, name: &str) -> Option<Node<'a, 'i>> {
        self.by.iter().find_map(|map| map.get(name).copied())
    }
}

/// The words of a `Name_array` or `IDREF_array`, as many as its `count` says.
fn names<'a>(ctx: &Ctx, array: Node<'a, '_>) -> Result<Vec<&'a str>, LoadError> {
    let words: Vec<&str> = array
        .text()
        .unwrap_or("")
        .split_ascii_whitespace()
        .collect();
    match ctx.uint_attr(array, "count")? {
        Some(c) if c > words.len() as u64 => {
            let msg = format!("count is {c} but {} names are present", words.len());
            Err(ctx.err(array, msg))
        }
        Some(c) => Ok(words[..c as usize].to_vec()),
        None => Ok(words),
    }
}

/// The `<input semantic=…>` of `parent`, which must have one.
fn semantic_input<'a, 'i>(
    ctx: &Ctx,
    parent: Node<'a, 'i>,
    semantic: &str,
) -> Result<Node<'a, 'i>, LoadError> {
    children(parent, "input")
        .find(|i| i.attribute("semantic") == Some(semantic))
        .ok_or_else(|| ctx.err(parent, format!("no {semantic} input")))
}

/// The INV_BIND_MATRIX source's row-major matrices, one per joint.
fn inverse_binds(ctx: &Ctx, joints: Node, count: usize) -> Result<Vec<DMat4>, LoadError> {
    let source = ctx.resolve(
        semantic_input(ctx, joints, "INV_BIND_MATRIX")?,
        "source",
        "source",
    )?;
    let (values, stride, found) = source_values(ctx, source, 16, 16)?;
    if found != count {
        let msg = format!("has {found} inverse bind matrices for {count} joints");
        return Err(ctx.err(source, msg));
    }
    let rows = values.chunks_exact(stride).take(count);
    Ok(rows
        .map(|r| {
            let a: [f64; 16] = std::array::from_fn(|k| r[k] as f64);
            DMat4::from_cols_array(&a).transpose()
        })
        .collect())
}

/// Where a `<vertex_weights>` influence keeps its joint and weight indices in `<v>`,
/// and the weights those index.
struct Influences {
    stride: usize,
    joint: usize,
    weight: usize,
    weights: Vec<f64>,
}

impl Influences {
    fn read(ctx: &Ctx, vw: Node) -> Result<Self, LoadError> {
        let joint = input_offset(ctx, semantic_input(ctx, vw, "JOINT")?)?;
        let weight_input = semantic_input(ctx, vw, "WEIGHT")?;
        let weight = input_offset(ctx, weight_input)?;
        let mut stride = 0;
        for input in children(vw, "input") {
            stride = stride.max(input_offset(ctx, input)? + 1);
        }
        let source = ctx.resolve(weight_input, "source", "source")?;
        let (values, step, count) = source_values(ctx, source, 1, 1)?;
        let weights = values.iter().step_by(step).take(count);
        Ok(Influences {
            stride,
            joint,
            weight,
            weights: weights.map(|&w| w as f64).collect(),
        })
    }
}

/// Each vertex's `Σ w_i·P_i` over its influences, `P_i` the pose of joint `i`
/// (`J_i·IB_i`). The vertex count must be the mesh's, and `<vcount>` must account
/// for every index of `<v>`.
fn blend(ctx: &mut Ctx, vw: Node, poses: &[DMat4], count: usize) -> Result<Vec<DMat4>, LoadError> {
    let influences = Influences::read(ctx, vw)?;
    let declared = ctx.uint_attr(vw, "count")?;
    if declared != Some(count as u64) {
        let said = declared.map_or("no count".to_string(), |c| format!("count {c}"));
        let msg = format!("{said}, but the skinned mesh has {count} vertices");
        return Err(ctx.err(vw, msg));
    }
    let vcount_node = child(vw, "vcount").ok_or_else(|| ctx.err(vw, "no <vcount>"))?;
    let vcount = ctx.numbers::<u32>(vcount_node)?;
    if vcount.len() != count {
        let msg = format!("has {} entries for {count} vertices", vcount.len());
        return Err(ctx.err(vcount_node, msg));
    }
    let v_node = child(vw, "v").ok_or_else(|| ctx.err(vw, "no <v>"))?;
    let v = ctx.numbers::<i64>(v_node)?;
    let needed: u64 = vcount
        .iter()
        .map(|&c| c as u64 * influences.stride as u64)
        .sum();
    if needed != v.len() as u64 {
        let msg = format!(
            "has {} indices, but <vcount> needs {needed} ({} per influence)",
            v.len(),
            influences.stride
        );
        return Err(ctx.err(v_node, msg));
    }
    let mut rest = v.as_slice();
    let mut out = Vec::with_capacity(count);
    for (vertex, &n) in vcount.iter().enumerate() {
        let (mine, tail) = rest.split_at(n as usize * influences.stride);
        rest = tail;
        let at = Site {
            vw,
            v: v_node,
            vertex,
        };
        out.push(vertex_matrix(ctx, &at, mine, &influences, poses)?);
    }
    Ok(out)
}

/// The elements and vertex an influence belongs to, for messages.
struct Site<'a, 'i> {
    vw: Node<'a, 'i>,
    v: Node<'a, 'i>,
    vertex: usize,
}

/// One vertex's `Σ w_i·P_i`, its weights normalised if they do not sum to 1. A
/// vertex without weight stays at its bind shape (as Blender leaves unweighted
/// vertices), with a warning.
fn vertex_matrix(
    ctx: &mut Ctx,
    at: &Site,
    indices: &[i64],
    influences: &Influences,
    poses: &[DMat4],
) -> Result<DMat4, LoadError> {
    let mut sum = DMat4::ZERO;
    let mut total = 0.0;
    for influence in indices.chunks_exact(influences.stride) {
        let (j, w) = (influence[influences.joint], influence[influences.weight]);
        let pose = match usize::try_from(j).ok().and_then(|j| poses.get(j)) {
            Some(p) => *p,
            None if j == BIND_SHAPE_JOINT => DMat4::IDENTITY,
            None => {
                let msg = format!(
                    "vertex {}: joint index {j} is out of range (the skin names {} joint(s); \
                     -1 is the bind shape)",
                    at.vertex,
                    poses.len()
                );
                return Err(ctx.err(at.v, msg));
            }
        };
        let Some(&weight) = usize::try_from(w)
            .ok()
            .and_then(|w| influences.weights.get(w))
        else {
            let msg = format!(
                "vertex {}: weight index {w} is out of range (only {} weights)",
                at.vertex,
                influences.weights.len()
            );
            return Err(ctx.err(at.v, msg));
        };
        sum += pose * weight;
        total += weight;
    }
    if total.abs() < 1e-6 {
        let msg = "a vertex has no joint weight; it stays at its bind shape";
        ctx.warn_once("unweighted vertex", at.vw, msg);
        return Ok(DMat4::IDENTITY);
    }
    if (total - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
        let msg = format!(
            "vertex {}'s weights sum to {total}, not 1; such weights are normalised",
            at.vertex
        );
        ctx.warn_once("weight sum", at.vw, msg);
        sum *= 1.0 / total;
    }
    Ok(sum)
}
