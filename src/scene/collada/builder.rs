//! Walks the visual scene and flattens its instances into a `Scene`.

use super::camera::read_camera;
use super::effects::read_material;
use super::lights::read_light;
use super::mesh::{parse_mesh, LocalMesh};
use super::transform::{linear, local_matrix, normal_matrix, point, up_axis_matrix};
use super::xml::{child, children, extension_technique, path, Ctx};
use super::LoadError;
use crate::geometry::Aabb;
use crate::lights::Light;
use crate::materials::Material;
use crate::scene::{CameraDesc, MeshInstance, Scene, Sphere, Triangle, NO_LIGHT};
use glam::{DMat4, DVec3, Vec3};
use roxmltree::{Document, Node, NodeId};
use std::collections::HashMap;
use std::rc::Rc;

/// Deepest `<node>` nesting accepted; real scenes use one or two levels.
const MAX_NODE_DEPTH: usize = 256;
/// Caps on the flattened scene, so that a small file instancing a mesh many
/// times cannot exhaust memory.
const MAX_TRIANGLES: usize = 1 << 24;
const MAX_VERTICES: usize = 1 << 24;

pub(crate) fn build(file: &str, doc: &Document) -> Result<Scene, LoadError> {
    let mut ctx = Ctx::new(file, doc);
    let up = up_axis_matrix(&mut ctx, doc);
    let mut b = Builder {
        ctx,
        scene: Scene::default(),
        meshes: HashMap::new(),
        materials: HashMap::new(),
        default_material: None,
        camera: None,
    };
    if let Some(vs) = b.visual_scene(doc.root_element())? {
        b.walk(vs, up)?;
    }
    Ok(b.finish(doc.root_element()))
}

/// An element waiting on the walk's explicit stack (no recursion, so deep
/// nesting cannot overflow the call stack).
enum Pending<'a, 'i> {
    Node {
        node: Node<'a, 'i>,
        parent: DMat4,
        depth: usize,
    },
    Instance {
        node: Node<'a, 'i>,
        world: DMat4,
    },
}

struct Builder<'a, 'i> {
    ctx: Ctx<'a, 'i>,
    scene: Scene,
    /// Meshes already read, by `<geometry>`, for geometry instanced more than once.
    meshes: HashMap<NodeId, Rc<LocalMesh<'a>>>,
    /// `Scene::materials` index of each `<material>` read.
    materials: HashMap<NodeId, u32>,
    default_material: Option<u32>,
    camera: Option<CameraDesc>,
}

impl<'a, 'i> Builder<'a, 'i> {
    /// `scene/instance_visual_scene@url`, else the first visual scene (with a warning).
    fn visual_scene(&mut self, root: Node<'a, 'i>) -> Result<Option<Node<'a, 'i>>, LoadError> {
        if let Some(ivs) = path(root, &["scene", "instance_visual_scene"]) {
            return self.ctx.resolve(ivs, "url", "visual_scene").map(Some);
        }
        let first = child(root, "library_visual_scenes").and_then(|l| child(l, "visual_scene"));
        match first {
            Some(_) => self
                .ctx
                .warn(root, "no <scene>; using the first <visual_scene>"),
            None => self.ctx.warn(root, "no visual scene; the scene is empty"),
        }
        Ok(first)
    }

    /// Visits nodes and instances in document order, composing `W = U·L_root·…·L_node`.
    fn walk(&mut self, visual_scene: Node<'a, 'i>, up: DMat4) -> Result<(), LoadError> {
        let mut stack = Vec::new();
        push_children(&mut stack, visual_scene, up, 0);
        while let Some(item) = stack.pop() {
            match item {
                Pending::Node {
                    node,
                    parent,
                    depth,
                } => {
                    if depth > MAX_NODE_DEPTH {
                        let msg = format!("nodes are nested deeper than {MAX_NODE_DEPTH} levels");
                        return Err(self.ctx.err(node, msg));
                    }
                    let world = parent * local_matrix(&mut self.ctx, node)?;
                    push_children(&mut stack, node, world, depth);
                }
                Pending::Instance { node, world } => self.instance(node, &world)?,
            }
        }
        Ok(())
    }

    fn instance(&mut self, node: Node<'a, 'i>, world: &DMat4) -> Result<(), LoadError> {
        match node.tag_name().name() {
            "instance_geometry" => self.instance_geometry(node, world),
            "instance_light" => {
                let Some(light) = self.optional_target(node, "light")? else {
                    return Ok(());
                };
                if let Some(l) = read_light(&mut self.ctx, light, world)? {
                    self.scene.lights.push(l);
                }
                Ok(())
            }
            "instance_camera" => {
                // The last camera in document order wins (spec §4).
                if let Some(camera) = self.optional_target(node, "camera")? {
                    self.camera = Some(read_camera(&mut self.ctx, camera, world)?);
                }
                Ok(())
            }
            other => {
                let msg = format!("<{other}> is not supported; skipped");
                self.ctx.warn(node, msg);
                Ok(())
            }
        }
    }

    /// The light or camera an instance names. A dangling URL there only
    /// loses that light or camera, so it is a warning (the CMU462 `CBgems.dae`
    /// instances a light it does not define); any other dangling URL is an error.
    fn optional_target(
        &mut self,
        inst: Node<'a, 'i>,
        tag: &str,
    ) -> Result<Option<Node<'a, 'i>>, LoadError> {
        let target = self.ctx.resolve_if_present(inst, "url", tag)?;
        if target.is_none() {
            let url = super::xml::clip(inst.attribute("url").unwrap_or_default());
            self.ctx.warn(
                inst,
                format!("url=\"{url}\" names nothing; the {tag} is skipped"),
            );
        }
        Ok(target)
    }

    fn instance_geometry(&mut self, inst: Node<'a, 'i>, world: &DMat4) -> Result<(), LoadError> {
        let geometry = self.ctx.resolve(inst, "url", "geometry")?;
        if let Some(mesh_node) = child(geometry, "mesh") {
            let mesh = match self.meshes.get(&geometry.id()) {
                Some(m) => Rc::clone(m),
                None => {
                    let m = Rc::new(parse_mesh(&mut self.ctx, mesh_node)?);
                    self.meshes.insert(geometry.id(), Rc::clone(&m));
                    m
                }
            };
            let materials = mesh
                .symbols
                .iter()
                .map(|s| self.bound_material(inst, *s))
                .collect::<Result<Vec<_>, _>>()?;
            return self.place_mesh(inst, &mesh, &materials, world);
        }
        match extension_technique(geometry).and_then(|t| child(t, "sphere")) {
            Some(sphere) => self.place_sphere(inst, sphere, world),
            None => {
                self.ctx.warn(
                    geometry,
                    "geometry has neither <mesh> nor <sphere>; skipped",
                );
                Ok(())
            }
        }
    }

    /// The material bound to `symbol` by the instance's `instance_material`s
    /// (spec §3): the matching one, else the first, else the default.
    fn bound_material(
        &mut self,
        inst: Node<'a, 'i>,
        symbol: Option<&str>,
    ) -> Result<u32, LoadError> {
        let bindings: Vec<Node> = path(inst, &["bind_material", "technique_common"])
            .map(|t| children(t, "instance_material").collect())
            .unwrap_or_default();
        let matching =
            symbol.and_then(|s| bindings.iter().find(|b| b.attribute("symbol") == Some(s)));
        let chosen = match (matching, bindings.first(), symbol) {
            (Some(b), _, _) => Some(*b),
            (None, Some(first), Some(s)) => {
                let msg = format!(
                    "material symbol \"{}\" is not bound; using the first instance_material",
                    super::xml::clip(s)
                );
                self.ctx.warn(inst, msg);
                Some(*first)
            }
            (None, first, None) => first.copied(),
            (None, None, Some(_)) => None,
        };
        match chosen {
            Some(b) => {
                let material = self.ctx.resolve(b, "target", "material")?;
                self.material_index(material)
            }
            None => Ok(self.default_material(inst)),
        }
    }

    fn material_index(&mut self, material: Node<'a, 'i>) -> Result<u32, LoadError> {
        if let Some(&i) = self.materials.get(&material.id()) {
            return Ok(i);
        }
        let m = read_material(&mut self.ctx, material)?;
        let i = self.push_material(m, display_name(material));
        self.materials.insert(material.id(), i);
        Ok(i)
    }

    fn default_material(&mut self, inst: Node) -> u32 {
        self.ctx.warn(
            inst,
            "no material bound; using the default Lambertian (albedo 0.5)",
        );
        match self.default_material {
            Some(i) => i,
            None => {
                let i = self.push_material(Material::default(), "(default)".into());
                self.default_material = Some(i);
                i
            }
        }
    }

    fn push_material(&mut self, m: Material, name: String) -> u32 {
        self.scene.materials.push(m);
        self.scene.material_names.push(name);
        (self.scene.materials.len() - 1) as u32
    }

    /// Appends a mesh instance in world space. Each triangle is wound so that
    /// `(p1−p0)×(p2−p0)` points to the side of its corner normals, which makes
    /// the winding alone give the front (spec §3).
    fn place_mesh(
        &mut self,
        inst: Node,
        mesh: &LocalMesh,
        materials: &[u32],
        world: &DMat4,
    ) -> Result<(), LoadError> {
        let s = &mut self.scene;
        if s.positions.len() + mesh.positions.len() > MAX_VERTICES
            || s.normals.len() + mesh.normals.len() > MAX_VERTICES
            || s.triangles.len() + mesh.triangles.len() > MAX_TRIANGLES
        {
            let msg = format!("scene exceeds {MAX_TRIANGLES} triangles or {MAX_VERTICES} vertices");
            return Err(self.ctx.err(inst, msg));
        }
        let (base_p, base_n) = (s.positions.len() as u32, s.normals.len() as u32);
        let mut used: Vec<u32> = materials.to_vec();
        used.sort_unstable();
        used.dedup();
        s.meshes.push(MeshInstance {
            name: inst.parent_element().map_or_else(String::new, display_name),
            first: s.triangles.len() as u32,
            count: mesh.triangles.len() as u32,
            materials: used,
        });
        for p in &mesh.positions {
            let q = point(world, p.as_dvec3()).as_vec3();
            if !q.is_finite() {
                return Err(self
                    .ctx
                    .err(inst, "a transformed vertex position is not finite"));
            }
            s.positions.push(q);
        }
        let nm = normal_matrix(world);
        s.normals.extend(mesh.normals.iter().map(|n| {
            let m = (nm * n.as_dvec3()).normalize_or_zero().as_vec3();
            if m.is_finite() {
                m
            } else {
                Vec3::ZERO
            }
        }));
        for t in &mesh.triangles {
            let mut v = t.v.map(|i| i + base_p);
            let mut n = t.n.map(|n| n.map(|i| i + base_n));
            let [p0, p1, p2] = v.map(|i| s.positions[i as usize]);
            if let Some(nn) = n {
                let sum: Vec3 = nn.iter().map(|&i| s.normals[i as usize]).sum();
                if (p1 - p0).cross(p2 - p0).dot(sum) < 0.0 {
                    v.swap(1, 2);
                    n = Some([nn[0], nn[2], nn[1]]);
                }
            }
            for p in [p0, p1, p2] {
                s.bounds.grow(p);
            }
            s.triangles.push(Triangle {
                v,
                n,
                material: materials[t.group as usize],
                light: NO_LIGHT,
            });
        }
        Ok(())
    }

    /// Centre `W·(0,0,0,1)`, radius `r·|W3·(1,0,0)|` (spec §3).
    fn place_sphere(
        &mut self,
        inst: Node<'a, 'i>,
        sphere: Node,
        world: &DMat4,
    ) -> Result<(), LoadError> {
        let r = self
            .ctx
            .child_scalar(sphere, "radius")?
            .ok_or_else(|| self.ctx.err(sphere, "missing <radius>"))?;
        if r <= 0.0 {
            return Err(self.ctx.err(sphere, format!("radius {r} is not positive")));
        }
        let w3 = linear(world);
        let (sx, sy, sz) = (
            (w3 * DVec3::X).length(),
            (w3 * DVec3::Y).length(),
            (w3 * DVec3::Z).length(),
        );
        if (sy - sx).abs() > 1e-4 * sx || (sz - sx).abs() > 1e-4 * sx {
            let msg = format!(
                "sphere under non-uniform scale ({sx:.4}, {sy:.4}, {sz:.4}); the x scale is used"
            );
            self.ctx.warn(inst, msg);
        }
        let centre = point(world, DVec3::ZERO).as_vec3();
        let radius = (r as f64 * sx) as f32;
        if !centre.is_finite() || !radius.is_finite() || radius <= 0.0 {
            let msg =
                format!("transformed sphere (centre {centre}, radius {radius}) is degenerate");
            return Err(self.ctx.err(inst, msg));
        }
        let material = self.bound_material(inst, None)?;
        let s = &mut self.scene;
        s.bounds = s.bounds.union(&Aabb::new(
            centre - Vec3::splat(radius),
            centre + Vec3::splat(radius),
        ));
        s.spheres.push(Sphere {
            centre,
            radius,
            material,
        });
        Ok(())
    }

    /// Appends each area light's two emitting triangles (after all mesh
    /// triangles, outside `bounds`) and settles the camera.
    fn finish(mut self, root: Node) -> Scene {
        for light in std::mem::take(&mut self.scene.lights) {
            match light {
                Light::Area(a) => {
                    self.scene.add_area_light(a);
                }
                other => self.scene.lights.push(other),
            }
        }
        self.scene.camera = match self.camera {
            Some(c) => c,
            None => {
                self.ctx
                    .warn(root, "no camera; using the default view down −Z");
                CameraDesc::default()
            }
        };
        self.scene.warnings = self.ctx.into_warnings();
        self.scene
    }
}

/// Pushes `parent`'s child nodes and instances so that they pop in document order.
fn push_children<'a, 'i>(
    stack: &mut Vec<Pending<'a, 'i>>,
    parent: Node<'a, 'i>,
    world: DMat4,
    depth: usize,
) {
    for c in parent
        .children()
        .filter(Node::is_element)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
    {
        match c.tag_name().name() {
            "node" => stack.push(Pending::Node {
                node: c,
                parent: world,
                depth: depth + 1,
            }),
            name if name.starts_with("instance_") => {
                stack.push(Pending::Instance { node: c, world })
            }
            _ => {}
        }
    }
}

/// An element's `name`, else its `id`, clipped for display.
fn display_name(n: Node) -> String {
    let name = n.attribute("name").or(n.attribute("id")).unwrap_or("");
    super::xml::clip(name)
}
