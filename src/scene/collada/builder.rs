//! Walks the visual scene and flattens its instances into a `Scene`.

use super::camera::{authoring_tool, course_placement, read_camera, writes_watts};
use super::effects::{read_material, TextureRef};
use super::lights::read_light;
use super::mesh::{parse_mesh, LocalMesh};
use super::skin;
use super::transform::{linear, local_matrix, normal_matrix, point, up_axis_matrix};
use super::xml::{child, children, extension_technique, path, Ctx};
use super::{LoadError, Resources};
use crate::geometry::Aabb;
use crate::lights::Light;
use crate::materials::Material;
use crate::scene::{CameraDesc, MeshInstance, Placement, Scene, Sphere, Triangle, NO_LIGHT};
use crate::texture::Texture;
use glam::{DMat4, DVec3, Vec2, Vec3};
use roxmltree::{Document, Node, NodeId};
use std::collections::HashMap;
use std::rc::Rc;
use std::sync::Arc;

/// Deepest `<node>` nesting accepted; real scenes use one or two levels.
const MAX_NODE_DEPTH: usize = 256;
/// Caps on the flattened scene, so that a small file instancing a mesh many
/// times cannot exhaust memory.
const MAX_TRIANGLES: usize = 1 << 24;
const MAX_VERTICES: usize = 1 << 24;
/// Cap on nodes visited, so that nodes instancing each other many times over
/// (`<instance_node>`) cannot make the walk run for ever.
const MAX_NODE_VISITS: usize = 1 << 22;
/// Controllers a `<skin>` or `<morph>` may chain through before reaching a geometry.
const MAX_CONTROLLER_CHAIN: usize = 16;
/// Largest coordinate a placed vertex or sphere may have: beyond it the `f32`
/// surface areas and slab distances of the BVH overflow.
const MAX_COORDINATE: f32 = 1e18;

pub(crate) fn build(
    file: &str,
    doc: &Document,
    resources: &dyn Resources,
) -> Result<Scene, LoadError> {
    let mut ctx = Ctx::new(file, doc);
    let (placement, placement_reason) = course_placement(doc);
    ctx.course_file = placement == Placement::Course;
    // The course's extension keeps the course's units whichever Blender wrote it.
    ctx.light_watts = !ctx.course_file && authoring_tool(doc).is_some_and(writes_watts);
    let up = up_axis_matrix(&mut ctx, doc);
    let mut b = Builder {
        ctx,
        scene: Scene::default(),
        meshes: HashMap::new(),
        materials: HashMap::new(),
        texcoords: HashMap::new(),
        images: HashMap::new(),
        default_material: None,
        camera: None,
        placement,
        dangling_camera: None,
        up,
        joint_scope: doc.root_element(),
        resources,
    };
    b.scene.placement_reason = placement_reason;
    if let Some(vs) = b.visual_scene(doc.root_element())? {
        b.joint_scope = vs;
        b.walk(vs, up)?;
    }
    if b.scene.meshes.is_empty() && b.scene.spheres.is_empty() {
        b.place_uninstanced_geometry(doc.root_element())?;
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
        depth: usize,
    },
}

/// What an `<instance_controller>` places: the `<skin>`s its controllers chain
/// through (outermost first; morphs add nothing) and the geometry they end at.
struct Chain<'a, 'i> {
    skins: Vec<Node<'a, 'i>>,
    geometry: Node<'a, 'i>,
}

struct Builder<'a, 'i, 'r> {
    ctx: Ctx<'a, 'i>,
    scene: Scene,
    /// Meshes already read, by `<geometry>`, for geometry instanced more than once.
    meshes: HashMap<NodeId, Rc<LocalMesh<'a>>>,
    /// `Scene::materials` index of each `<material>` read.
    materials: HashMap<NodeId, u32>,
    /// The `texcoord` semantic of each textured material's texture, by material index.
    texcoords: HashMap<u32, Option<&'a str>>,
    /// `Scene::textures` index of each image read, by `<image>` and wrap modes.
    images: HashMap<(NodeId, [u8; 2]), u32>,
    default_material: Option<u32>,
    camera: Option<CameraDesc>,
    placement: Placement,
    /// The first `<instance_camera>` that named nothing (warned in `finish`).
    dangling_camera: Option<Node<'a, 'i>>,
    /// `U`, the up-axis conversion (skinned meshes are placed by it alone).
    up: DMat4,
    /// Where a skin's joints are looked for when its instance names no `<skeleton>`:
    /// the visual scene.
    joint_scope: Node<'a, 'i>,
    resources: &'r dyn Resources,
}

impl<'a, 'i> Builder<'a, 'i, '_> {
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
        let mut visits = 0usize;
        while let Some(item) = stack.pop() {
            match item {
                Pending::Node {
                    node,
                    parent,
                    depth,
                } => {
                    if depth > MAX_NODE_DEPTH {
                        let msg = format!(
                            "nodes are nested (or instance each other) deeper than \
                             {MAX_NODE_DEPTH} levels"
                        );
                        return Err(self.ctx.err(node, msg));
                    }
                    visits += 1;
                    if visits > MAX_NODE_VISITS {
                        let msg = format!("more than {MAX_NODE_VISITS} node instances");
                        return Err(self.ctx.err(node, msg));
                    }
                    let world = parent * local_matrix(&mut self.ctx, node)?;
                    push_children(&mut stack, node, world, depth);
                }
                Pending::Instance { node, world, depth } => {
                    if node.has_tag_name("instance_node") {
                        // The node it names is placed here, as if it were a child.
                        let target = self.ctx.resolve_if_present(node, "url", "node")?;
                        match target {
                            Some(target) => stack.push(Pending::Node {
                                node: target,
                                parent: world,
                                depth: depth + 1,
                            }),
                            None => {
                                let url = super::xml::clip(node.attribute("url").unwrap_or(""));
                                let msg =
                                    format!("url=\"{url}\" names nothing in this file; skipped");
                                self.ctx.warn(node, msg);
                            }
                        }
                    } else {
                        self.instance(node, &world)?;
                    }
                }
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
                    let c = read_camera(&mut self.ctx, camera, world, self.placement)?;
                    self.camera = Some(c);
                }
                Ok(())
            }
            "instance_controller" => self.instance_controller(node),
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
            if tag == "camera" {
                // Warned in `finish`, with what follows from it: one problem, one warning.
                self.dangling_camera.get_or_insert(inst);
            } else {
                let msg = format!("url=\"{url}\" names nothing in this file; the {tag} is skipped");
                self.ctx.warn(inst, msg);
            }
        }
        Ok(target)
    }

    /// A file whose visual scene instances no geometry at all (some exporters write
    /// their meshes to the library only): each `<geometry>` with a `<mesh>` is placed
    /// once, untransformed, as assimp and other importers do, with one warning. Its
    /// primitives' material symbols are taken as material ids where they name one.
    fn place_uninstanced_geometry(&mut self, root: Node<'a, 'i>) -> Result<(), LoadError> {
        let geometries: Vec<Node> = children(root, "library_geometries")
            .flat_map(|l| children(l, "geometry"))
            .filter(|g| child(*g, "mesh").is_some())
            .collect();
        let Some(&first) = geometries.first() else {
            return Ok(());
        };
        let msg = format!(
            "the visual scene instances no geometry; each of the {} meshes of \
             <library_geometries> is placed once, untransformed",
            geometries.len()
        );
        self.ctx.warn(first, msg);
        for g in geometries {
            let Some(mesh_node) = child(g, "mesh") else {
                continue;
            };
            let mesh = parse_mesh(&mut self.ctx, mesh_node)?;
            let mut materials = Vec::with_capacity(mesh.symbols.len());
            for symbol in &mesh.symbols {
                let target = symbol
                    .and_then(|s| self.ctx.by_id(s))
                    .filter(|m| m.has_tag_name("material"));
                materials.push(match target {
                    Some(m) => self.material_index(m)?,
                    None => self.default_material(g),
                });
            }
            let uv_sets: Vec<_> = materials
                .iter()
                .map(|&m| self.textured(m).then_some(None))
                .collect();
            let up = self.up;
            self.place_mesh(g, &mesh, &materials, &uv_sets, &up)?;
        }
        Ok(())
    }

    fn textured(&self, material: u32) -> bool {
        self.scene
            .material_textures
            .get(material as usize)
            .is_some_and(Option::is_some)
    }

    /// A skinned mesh posed by COLLADA's skinning equation at the visual scene's pose
    /// of its joints (`skin::vertex_matrices`). The equation leaves the mesh in world
    /// space, so the instancing node's transform does not enter (only the up-axis
    /// conversion does). A skin without joints or weights stays at its bind shape
    /// (`bind_shape_matrix · v`), a morph is read as its base mesh.
    fn instance_controller(&mut self, inst: Node<'a, 'i>) -> Result<(), LoadError> {
        let Some(chain) = self.controller_chain(inst)? else {
            return Ok(());
        };
        match self.skinnable_mesh(&chain)? {
            Some(mesh) => self.place_skinned(inst, &chain, &mesh),
            None => self.place_at_bind_pose(inst, &chain),
        }
    }

    /// The chain's mesh, if a skin of the chain has joints and weights to pose it by.
    fn skinnable_mesh(
        &mut self,
        chain: &Chain<'a, 'i>,
    ) -> Result<Option<Rc<LocalMesh<'a>>>, LoadError> {
        if !chain.skins.iter().any(|&s| skin::has_joints(s)) {
            return Ok(None);
        }
        let mesh = self.local_mesh(chain.geometry)?;
        Ok(mesh.filter(|m| m.vertices.is_some()))
    }

    /// Places a posed copy of the mesh; the cached mesh stays as read, for plain
    /// instances of the same geometry.
    fn place_skinned(
        &mut self,
        inst: Node<'a, 'i>,
        chain: &Chain<'a, 'i>,
        mesh: &LocalMesh<'a>,
    ) -> Result<(), LoadError> {
        self.ctx.warn_once(
            "skin",
            inst,
            "skinned mesh placed at the visual scene's joint pose; animation is ignored",
        );
        let count = mesh.vertices.map_or(0, |(_, n)| n as usize);
        // A skin of a skin poses the inner skin's result: the innermost applies first.
        let mut pose = vec![DMat4::IDENTITY; count];
        for &s in chain.skins.iter().rev() {
            let m = skin::vertex_matrices(&mut self.ctx, s, inst, self.joint_scope, count)?;
            for (p, m) in pose.iter_mut().zip(m) {
                *p = m * *p;
            }
        }
        let up = self.up;
        self.place_bound_mesh(inst, &skin::posed(mesh, &pose), &up)
    }

    /// `BSM_outer · … · BSM_inner · v`: each skin's bind shape, the innermost first.
    fn place_at_bind_pose(
        &mut self,
        inst: Node<'a, 'i>,
        chain: &Chain<'a, 'i>,
    ) -> Result<(), LoadError> {
        self.ctx.warn_once(
            "controller",
            inst,
            "skinned or morphed mesh placed at its bind pose (a skin without joint weights \
             at its bind shape, a morph as its base mesh); animation is ignored",
        );
        let mut bind = DMat4::IDENTITY;
        for &s in &chain.skins {
            bind *= skin::bind_shape(&self.ctx, s)?;
        }
        self.instance_geometry_node(inst, chain.geometry, &(self.up * bind))
    }

    /// The controllers an instance chains through to its geometry; `None` (warned)
    /// for a controller of neither skin nor morph.
    fn controller_chain(&mut self, inst: Node<'a, 'i>) -> Result<Option<Chain<'a, 'i>>, LoadError> {
        let mut controller = self.ctx.resolve(inst, "url", "controller")?;
        let mut skins = Vec::new();
        for _ in 0..MAX_CONTROLLER_CHAIN {
            let Some(kind) = controller
                .children()
                .find(|c| c.has_tag_name("skin") || c.has_tag_name("morph"))
            else {
                self.ctx.warn(
                    controller,
                    "controller has neither <skin> nor <morph>; skipped",
                );
                return Ok(None);
            };
            if kind.has_tag_name("skin") {
                skins.push(kind);
            }
            let url = kind.attribute("source").unwrap_or("");
            let target = url.strip_prefix('#').and_then(|id| self.ctx.by_id(id));
            match target {
                Some(geometry) if geometry.has_tag_name("geometry") => {
                    return Ok(Some(Chain { skins, geometry }));
                }
                Some(t) if t.has_tag_name("controller") => controller = t,
                _ => {
                    let msg = format!(
                        "source=\"{}\" names no geometry or controller",
                        super::xml::clip(url)
                    );
                    return Err(self.ctx.err(kind, msg));
                }
            }
        }
        let msg = format!("controllers chain more than {MAX_CONTROLLER_CHAIN} deep");
        Err(self.ctx.err(inst, msg))
    }

    fn instance_geometry(&mut self, inst: Node<'a, 'i>, world: &DMat4) -> Result<(), LoadError> {
        let geometry = self.ctx.resolve(inst, "url", "geometry")?;
        self.instance_geometry_node(inst, geometry, world)
    }

    fn instance_geometry_node(
        &mut self,
        inst: Node<'a, 'i>,
        geometry: Node<'a, 'i>,
        world: &DMat4,
    ) -> Result<(), LoadError> {
        if let Some(mesh) = self.local_mesh(geometry)? {
            return self.place_bound_mesh(inst, &mesh, world);
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

    /// The geometry's `<mesh>`, read once per geometry (posing a skin copies it).
    fn local_mesh(
        &mut self,
        geometry: Node<'a, 'i>,
    ) -> Result<Option<Rc<LocalMesh<'a>>>, LoadError> {
        let Some(mesh_node) = child(geometry, "mesh") else {
            return Ok(None);
        };
        if let Some(m) = self.meshes.get(&geometry.id()) {
            return Ok(Some(Rc::clone(m)));
        }
        let m = Rc::new(parse_mesh(&mut self.ctx, mesh_node)?);
        self.meshes.insert(geometry.id(), Rc::clone(&m));
        Ok(Some(m))
    }

    /// Places `mesh` with the materials the instance binds to its symbols.
    fn place_bound_mesh(
        &mut self,
        inst: Node<'a, 'i>,
        mesh: &LocalMesh,
        world: &DMat4,
    ) -> Result<(), LoadError> {
        let materials = mesh
            .symbols
            .iter()
            .map(|s| self.bound_material(inst, *s))
            .collect::<Result<Vec<_>, _>>()?;
        let uv_sets = materials
            .iter()
            .map(|&(m, set)| self.textured(m).then_some(set))
            .collect::<Vec<_>>();
        let materials: Vec<u32> = materials.iter().map(|&(m, _)| m).collect();
        self.place_mesh(inst, mesh, &materials, &uv_sets, world)
    }

    /// The material bound to `symbol` by the instance's `instance_material`s
    /// (spec §3): the matching one, else the first, else the default; and the
    /// TEXCOORD set its texture reads (`Some(set)` from a `<bind_vertex_input>`,
    /// `None` for the mesh's first set). A binding whose target names nothing
    /// falls back to the default material with a warning, as other importers do.
    fn bound_material(
        &mut self,
        inst: Node<'a, 'i>,
        symbol: Option<&str>,
    ) -> Result<(u32, Option<u32>), LoadError> {
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
        let Some(b) = chosen else {
            return Ok((self.default_material(inst), None));
        };
        let Some(material) = self.ctx.resolve_if_present(b, "target", "material")? else {
            let target = super::xml::clip(b.attribute("target").unwrap_or(""));
            let msg = format!(
                "target=\"{target}\" names nothing in this file; using the default material"
            );
            self.ctx.warn(b, msg);
            return Ok((self.default_index(), None));
        };
        let index = self.material_index(material)?;
        let set = match self.texcoords.get(&index) {
            Some(Some(semantic)) => children(b, "bind_vertex_input")
                .find(|v| {
                    v.attribute("semantic") == Some(semantic)
                        && v.attribute("input_semantic")
                            .is_none_or(|s| s == "TEXCOORD")
                })
                .and_then(|v| v.attribute("input_set"))
                .and_then(|s| s.trim().parse().ok()),
            _ => None,
        };
        Ok((index, set))
    }

    fn material_index(&mut self, material: Node<'a, 'i>) -> Result<u32, LoadError> {
        if let Some(&i) = self.materials.get(&material.id()) {
            return Ok(i);
        }
        let read = read_material(&mut self.ctx, material)?;
        let mut m = read.material;
        let texture = match read.texture {
            Some(t) => self.texture_index(&t)?,
            None => None,
        };
        if let (None, Some(albedo)) = (texture, read.texture.and_then(|t| t.fallback)) {
            // The image could not be read: its fallback colour stands in (warned).
            m = Material {
                bsdf: Material::lambertian(albedo).bsdf,
                ..m
            };
        }
        let i = self.push_material(m, display_name(material));
        if let Some(t) = texture {
            let names = &mut self.scene.material_textures;
            names.resize(i as usize, None);
            names.push(Some(t));
            self.texcoords
                .insert(i, read.texture.and_then(|t| t.texcoord));
        }
        self.materials.insert(material.id(), i);
        Ok(i)
    }

    /// The texture of `t`'s image, loaded once per image and wrap modes. A file
    /// that cannot be read is an error, unless the effect gives a colour to fall
    /// back on (`TextureRef::fallback`): then a warning, and the colour alone.
    fn texture_index(&mut self, t: &TextureRef<'a, 'i>) -> Result<Option<u32>, LoadError> {
        let key = (t.image.id(), [t.wrap_s as u8, t.wrap_t as u8]);
        if let Some(&i) = self.images.get(&key) {
            return Ok(Some(i));
        }
        // COLLADA 1.4: <init_from>path</init_from>; 1.5: <init_from><ref>path</ref>.
        let init = child(t.image, "init_from").map(|i| child(i, "ref").unwrap_or(i));
        let uri = init.and_then(|n| n.text()).map(str::trim).unwrap_or("");
        let at = init.unwrap_or(t.image);
        if uri.is_empty() {
            let msg = "image has no file name (<init_from>)";
            return self.missing_texture(t, at, msg.to_string());
        }
        let loaded = self
            .resources
            .read(uri)
            .and_then(|(name, bytes)| Texture::decode(&name, &bytes));
        match loaded {
            Ok(mut tex) => {
                tex.wrap_s = t.wrap_s;
                tex.wrap_t = t.wrap_t;
                self.scene.textures.push(Arc::new(tex));
                let i = (self.scene.textures.len() - 1) as u32;
                self.images.insert(key, i);
                Ok(Some(i))
            }
            Err(why) => {
                let msg = format!("image \"{}\": {why}", super::xml::clip(uri));
                self.missing_texture(t, at, msg)
            }
        }
    }

    fn missing_texture(
        &mut self,
        t: &TextureRef<'a, 'i>,
        at: Node<'a, 'i>,
        msg: String,
    ) -> Result<Option<u32>, LoadError> {
        if t.fallback.is_some() {
            self.ctx
                .warn(at, format!("{msg}; the material's colour is used instead"));
            Ok(None)
        } else {
            Err(self.ctx.err(at, msg))
        }
    }

    /// The default material for an instance that binds none (warned once per file:
    /// exporters that write no bindings write none for every node).
    fn default_material(&mut self, inst: Node) -> u32 {
        self.ctx.warn_once(
            "unbound",
            inst,
            "no material bound; using the default Lambertian (albedo 0.5)",
        );
        self.default_index()
    }

    fn default_index(&mut self) -> u32 {
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
        uv_sets: &[Option<Option<u32>>],
        world: &DMat4,
    ) -> Result<(), LoadError> {
        if uv_sets.iter().any(Option::is_some) && mesh.uv_sets.is_empty() {
            self.ctx.warn(
                inst,
                "a textured material is bound to a mesh without TEXCOORD; the texture is read at (0, 0)",
            );
        }
        let missing = uv_sets.iter().flatten().flatten();
        if let (Some(&set), Some(first)) = (
            missing
                .into_iter()
                .find(|&&s| !mesh.uv_sets.iter().any(|u| u.set == s)),
            mesh.uv_sets.first(),
        ) {
            let msg = format!(
                "<bind_vertex_input input_set=\"{set}\"> names a TEXCOORD set the mesh lacks; its set {} is used",
                first.set
            );
            self.ctx.warn_once("texcoord set", inst, msg);
        }
        let s = &mut self.scene;
        if s.positions.len() + mesh.positions.len() > MAX_VERTICES
            || s.normals.len() + mesh.normals.len() > MAX_VERTICES
            || s.triangles.len() + mesh.triangles.len() > MAX_TRIANGLES
        {
            let msg = format!("scene exceeds {MAX_TRIANGLES} triangles or {MAX_VERTICES} vertices");
            return Err(self.ctx.err(inst, msg));
        }
        let (base_p, base_n) = (s.positions.len() as u32, s.normals.len() as u32);
        let textured = uv_sets.iter().any(Option::is_some);
        let base_uv = s.uvs.len() as u32;
        if textured {
            s.uvs.extend_from_slice(&mesh.uvs);
            s.uvs.push(Vec2::ZERO);
        }
        let origin_uv = base_uv + mesh.uvs.len() as u32;
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
            if !q.is_finite() || q.abs().max_element() > MAX_COORDINATE {
                let msg = format!(
                    "a transformed vertex position has a coordinate of {:e}: not finite or beyond ±{MAX_COORDINATE:e}",
                    q.abs().max_element()
                );
                return Err(self.ctx.err(inst, msg));
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
        let mut flat = 0;
        for (k, t) in mesh.triangles.iter().enumerate() {
            let mut v = t.v.map(|i| i + base_p);
            let mut n = t.n.map(|n| n.map(|i| i + base_n));
            let mut uv = uv_sets[t.group as usize].map(|set| {
                mesh.triangle_uvs(set, k)
                    .map_or([origin_uv; 3], |c| c.map(|i| i + base_uv))
            });
            let [p0, p1, p2] = v.map(|i| s.positions[i as usize]);
            let face_normal = (p1 - p0).cross(p2 - p0);
            if face_normal == Vec3::ZERO {
                flat += 1;
            }
            if let Some(nn) = n {
                let sum: Vec3 = nn.iter().map(|&i| s.normals[i as usize]).sum();
                if face_normal.dot(sum) < 0.0 {
                    v.swap(1, 2);
                    n = Some([nn[0], nn[2], nn[1]]);
                    uv = uv.map(|c| [c[0], c[2], c[1]]);
                }
            }
            if uv.is_some() {
                s.triangle_uvs.resize(s.triangles.len(), None);
                s.triangle_uvs.push(uv);
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
        if flat > 0 && flat == mesh.triangles.len() {
            // A zero scale, or a mesh of slivers: nothing to see or to light.
            let msg = format!(
                "all {flat} triangles have zero area once placed; the mesh renders nothing"
            );
            self.ctx.warn(inst, msg);
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
        let extent = centre.abs().max_element() + radius;
        if extent > MAX_COORDINATE && extent.is_finite() && radius > 0.0 {
            let msg = format!(
                "transformed sphere reaches a coordinate of {extent:e}, beyond ±{MAX_COORDINATE:e}"
            );
            return Err(self.ctx.err(inst, msg));
        }
        if !centre.is_finite() || !radius.is_finite() || radius <= 0.0 {
            let msg =
                format!("transformed sphere (centre {centre}, radius {radius}) is degenerate");
            return Err(self.ctx.err(inst, msg));
        }
        let (material, _) = self.bound_material(inst, None)?;
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
        let dangling = self.dangling_camera.map(|inst| {
            let url = super::xml::clip(inst.attribute("url").unwrap_or_default());
            (inst, format!("url=\"{url}\" names nothing in this file"))
        });
        self.scene.camera = match self.camera {
            Some(c) => {
                if let Some((inst, msg)) = dangling {
                    self.ctx.warn(inst, format!("{msg}; the camera is skipped"));
                }
                c
            }
            None => {
                match dangling {
                    Some((inst, msg)) => self
                        .ctx
                        .warn(inst, format!("{msg}; using the default view down −Z")),
                    None => self
                        .ctx
                        .warn(root, "no camera; using the default view down −Z"),
                }
                // Without a camera position the course's rule places the eye whatever
                // the placement (`ember info` says so).
                CameraDesc {
                    placement: self.placement,
                    ..CameraDesc::default()
                }
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
            name if name.starts_with("instance_") => stack.push(Pending::Instance {
                node: c,
                world,
                depth,
            }),
            _ => {}
        }
    }
}

/// An element's `name`, else its `id`, clipped for display.
fn display_name(n: Node) -> String {
    let name = n.attribute("name").or(n.attribute("id")).unwrap_or("");
    super::xml::clip(name)
}
