//! Node transforms and the up-axis conversion (spec §2). Matrices are composed
//! in f64 so long chains of nested nodes do not accumulate f32 error.

use super::xml::{child, Ctx};
use super::LoadError;
use glam::{DMat3, DMat4, DVec3, DVec4};
use roxmltree::{Document, Node};

/// `U`: maps the file's up axis to the renderer's +Y-up world.
pub(crate) fn up_axis_matrix(ctx: &mut Ctx, doc: &Document) -> DMat4 {
    let Some(node) = child(doc.root_element(), "asset").and_then(|a| child(a, "up_axis")) else {
        return DMat4::IDENTITY;
    };
    let rows: [[f64; 3]; 3] = match node.text().unwrap_or("").trim() {
        "Y_UP" => return DMat4::IDENTITY,
        // (x, y, z) → (−x, z, y)
        "Z_UP" => [[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
        // (x, y, z) → (y, x, −z)
        "X_UP" => [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]],
        other => {
            let msg = format!(
                "unknown up axis \"{}\"; using Y_UP",
                super::xml::clip(other)
            );
            ctx.warn(node, msg);
            return DMat4::IDENTITY;
        }
    };
    DMat4::from_mat3(DMat3::from_cols_array_2d(&rows).transpose())
}

/// `L = T1·T2·…·Tn` over the transform children of a `<node>`, in document order.
pub(crate) fn local_matrix(ctx: &mut Ctx, node: Node) -> Result<DMat4, LoadError> {
    let mut m = DMat4::IDENTITY;
    for t in node.children().filter(Node::is_element) {
        let step = match t.tag_name().name() {
            "matrix" => matrix(ctx, t)?,
            "translate" => DMat4::from_translation(DVec3::from(ctx.exact::<3>(t)?)),
            "scale" => DMat4::from_scale(DVec3::from(ctx.exact::<3>(t)?)),
            "rotate" => rotation(ctx, t)?,
            "lookat" => look_at(ctx, t)?,
            "skew" => {
                ctx.warn(t, "transform is not supported; ignored");
                continue;
            }
            _ => continue,
        };
        m *= step;
    }
    Ok(m)
}

/// A `<node>`'s matrix in the file's frame (without `U`): the `local_matrix` of each
/// enclosing `<node>` from the outermost down. Skinning reads joints by it, wherever
/// the walk has got to.
pub(crate) fn node_world(ctx: &mut Ctx, node: Node) -> Result<DMat4, LoadError> {
    let chain: Vec<Node> = node
        .ancestors()
        .filter(|n| n.has_tag_name("node"))
        .collect();
    let mut m = DMat4::IDENTITY;
    for n in chain.into_iter().rev() {
        m *= local_matrix(ctx, n)?;
    }
    Ok(m)
}

/// A row-major `<matrix>`; missing trailing entries are 0 (spec §2).
fn matrix(ctx: &mut Ctx, node: Node) -> Result<DMat4, LoadError> {
    let v = ctx.numbers::<f64>(node)?;
    match v.len() {
        0 => return Err(ctx.err(node, "matrix has no numbers")),
        1..=15 => ctx.warn(
            node,
            format!(
                "matrix has {} numbers instead of 16; the missing entries are taken as 0",
                v.len()
            ),
        ),
        16 => {}
        n => return Err(ctx.err(node, format!("matrix has {n} numbers, expected 16"))),
    }
    let mut a = [0.0; 16];
    a[..v.len()].copy_from_slice(&v);
    // glam is column-major; the file is row-major.
    Ok(DMat4::from_cols_array(&a).transpose())
}

/// A skin's row-major `<bind_shape_matrix>`. Unlike a node's `<matrix>`, a short one is
/// refused: padded with zeros it would send every vertex to infinity.
pub(crate) fn bind_shape_matrix(ctx: &Ctx, node: Node) -> Result<DMat4, LoadError> {
    let v = ctx.numbers::<f64>(node)?;
    let Ok(a) = <[f64; 16]>::try_from(v.as_slice()) else {
        let msg = format!(
            "has {} numbers; a bind shape matrix needs 16 (a row-major 4x4 matrix)",
            v.len()
        );
        return Err(ctx.err(node, msg));
    };
    Ok(DMat4::from_cols_array(&a).transpose())
}

/// `<rotate> ax ay az deg`: right-handed rotation about the axis. A zero axis
/// (`0 0 0 0`, written by some animation exporters) names no rotation: the identity.
fn rotation(ctx: &mut Ctx, node: Node) -> Result<DMat4, LoadError> {
    let [x, y, z, deg] = ctx.exact::<4>(node)?;
    let axis = DVec3::new(x, y, z);
    if axis.length_squared() == 0.0 {
        ctx.warn_once(
            "zero axis",
            node,
            "rotation axis is zero; read as no rotation",
        );
        return Ok(DMat4::IDENTITY);
    }
    Ok(DMat4::from_axis_angle(axis.normalize(), deg.to_radians()))
}

/// `<lookat>` eye, interest point, up: the frame at `eye` whose −Z points at the
/// interest point and whose +Y is `up` made orthogonal to it (Maya and XSI write it
/// for cameras). A degenerate one (eye on the interest point, up along the view) is
/// the translation alone, with a warning.
fn look_at(ctx: &mut Ctx, node: Node) -> Result<DMat4, LoadError> {
    let v = ctx.exact::<9>(node)?;
    let (eye, target, up) = (
        DVec3::new(v[0], v[1], v[2]),
        DVec3::new(v[3], v[4], v[5]),
        DVec3::new(v[6], v[7], v[8]),
    );
    let f = (target - eye).normalize_or_zero();
    let r = f.cross(up).normalize_or_zero();
    if f == DVec3::ZERO || r == DVec3::ZERO {
        ctx.warn(
            node,
            "degenerate lookat (no view direction or up along it); only its eye is used",
        );
        return Ok(DMat4::from_translation(eye));
    }
    let u = r.cross(f);
    Ok(DMat4::from_cols(
        r.extend(0.0),
        u.extend(0.0),
        (-f).extend(0.0),
        eye.extend(1.0),
    ))
}

/// The linear part `W3` of a transform.
pub(crate) fn linear(m: &DMat4) -> DMat3 {
    DMat3::from_mat4(*m)
}

/// `W·p` for a point.
pub(crate) fn point(m: &DMat4, p: DVec3) -> DVec3 {
    let h = *m * DVec4::new(p.x, p.y, p.z, 1.0);
    // A non-affine bottom row is honoured; w = 0 yields a non-finite point the caller rejects.
    h.truncate() / h.w
}

/// The matrix taking normals: `W3^{-T}` up to a positive scale (normals are
/// normalized afterwards). The cofactor form stays defined for singular `W3`.
pub(crate) fn normal_matrix(m: &DMat4) -> DMat3 {
    let w = linear(m);
    let cofactor = DMat3::from_cols(
        w.y_axis.cross(w.z_axis),
        w.z_axis.cross(w.x_axis),
        w.x_axis.cross(w.y_axis),
    );
    if w.determinant() < 0.0 {
        -cofactor
    } else {
        cofactor
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookat_points_minus_z_at_the_interest_point() {
        let doc = roxmltree::Document::parse("<lookat>1 2 3  1 2 -7  0 1 0</lookat>").unwrap();
        let mut ctx = Ctx::new("t.dae", &doc);
        let m = look_at(&mut ctx, doc.root_element()).unwrap();
        assert!((point(&m, DVec3::ZERO) - DVec3::new(1.0, 2.0, 3.0)).length() < 1e-12);
        assert!((linear(&m) * DVec3::NEG_Z - DVec3::NEG_Z).length() < 1e-12);
        let doc = roxmltree::Document::parse("<lookat>0 0 0  1 0 0  0 0 1</lookat>").unwrap();
        let mut ctx = Ctx::new("t.dae", &doc);
        let m = look_at(&mut ctx, doc.root_element()).unwrap();
        assert!((linear(&m) * DVec3::NEG_Z - DVec3::X).length() < 1e-12);
        assert!((linear(&m) * DVec3::Y - DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn normal_matrix_is_inverse_transpose_direction() {
        let m = DMat4::from_cols_array_2d(&[
            [2.0, 0.0, 0.0, 0.0],
            [1.0, 3.0, 0.0, 0.0],
            [0.0, 0.5, -1.0, 0.0],
            [4.0, 5.0, 6.0, 1.0],
        ]);
        let expected = linear(&m).inverse().transpose();
        let n = normal_matrix(&m);
        for v in [DVec3::X, DVec3::Y, DVec3::new(0.3, -0.7, 0.2)] {
            let a = (expected * v).normalize();
            let b = (n * v).normalize();
            assert!((a - b).length() < 1e-12, "{a} vs {b}");
        }
    }
}
