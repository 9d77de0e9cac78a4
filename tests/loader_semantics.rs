//! Spec §1-6 features the shipped scenes do not exercise: up axes, transform
//! kinds and order, nested nodes, primitive kinds and offsets, normals,
//! material selection and binding, camera and light rules.

use crate::common;

use common::{geometry_instance, parse_ok, quad_instance, scene_doc};
use ember::lights::{AreaLight, Light};
use ember::materials::Material;
use ember::scene::Scene;
use ember::Vec3;

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

/// World position of the quad's local vertex (1, 0, 0) under `transforms`.
fn corner_under(up: &str, transforms: &str) -> Vec3 {
    let nodes = format!("<node>{transforms}{}</node>", quad_instance());
    parse_ok(&scene_doc(up, "", &nodes)).positions[1]
}

#[test]
fn up_axis_conversion() {
    assert!(close(corner_under("Y_UP", ""), Vec3::X));
    // Z_UP: (x, y, z) → (−x, z, y); X_UP: (x, y, z) → (y, x, −z).
    assert!(close(
        corner_under("Z_UP", "<translate>0 2 3</translate>"),
        Vec3::new(-1.0, 3.0, 2.0)
    ));
    assert!(close(
        corner_under("X_UP", "<translate>0 2 3</translate>"),
        Vec3::new(2.0, 1.0, -3.0)
    ));
}

#[test]
fn transform_kinds_and_document_order() {
    let rotate = corner_under("Y_UP", "<rotate>0 0 1 90</rotate>");
    assert!(close(rotate, Vec3::Y), "right-handed about +z: {rotate}");
    // L = T·S: scale first, then translate.
    let ts = corner_under("Y_UP", "<translate>1 0 0</translate><scale>2 3 4</scale>");
    assert!(close(ts, Vec3::new(3.0, 0.0, 0.0)), "{ts}");
    let st = corner_under("Y_UP", "<scale>2 3 4</scale><translate>1 0 0</translate>");
    assert!(close(st, Vec3::new(4.0, 0.0, 0.0)), "{st}");
    // Row-major: the translation is the last column.
    let m = corner_under(
        "Y_UP",
        "<matrix>1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1</matrix>",
    );
    assert!(close(m, Vec3::new(6.0, 6.0, 7.0)), "{m}");
}

#[test]
fn nested_nodes_compose_parent_first() {
    let nodes = format!(
        "<node><translate>0 5 0</translate><node><scale>2 2 2</scale>{}</node></node>",
        quad_instance()
    );
    let s = parse_ok(&scene_doc("Y_UP", "", &nodes));
    assert!(
        close(s.positions[1], Vec3::new(2.0, 5.0, 0.0)),
        "{}",
        s.positions[1]
    );
}

/// A geometry `id` whose only primitive is `prim` over the template's quad
/// positions and a second normal source `(0,0,1), (0,0,−1)`.
fn geometry(id: &str, prim: &str) -> String {
    format!(
        r##"<library_geometries><geometry id="{id}"><mesh>
          <source id="{id}-pos"><float_array id="{id}-pos-a" count="15">0 0 0 1 0 0 1 1 0 0 1 0 -1 0.5 0</float_array></source>
          <source id="{id}-nrm"><float_array id="{id}-nrm-a" count="6">0 0 1 0 0 -1</float_array></source>
          <source id="{id}-uv"><float_array id="{id}-uv-a" count="2">0 0</float_array></source>
          <vertices id="{id}-vtx"><input semantic="POSITION" source="#{id}-pos"/></vertices>
          {prim}
        </mesh></geometry></library_geometries>"##
    )
}

fn load_geometry(prim: &str) -> Scene {
    let nodes = format!(
        "<node>{}</node>",
        geometry_instance("g", "grey-sym", "grey")
    );
    parse_ok(&scene_doc("Y_UP", &geometry("g", prim), &nodes))
}

#[test]
fn triangles_with_permuted_offsets() {
    let s = load_geometry(
        r##"<triangles material="grey-sym" count="1">
          <input semantic="NORMAL" source="#g-nrm" offset="0"/>
          <input semantic="TEXCOORD" source="#g-uv" offset="2"/>
          <input semantic="VERTEX" source="#g-vtx" offset="1"/>
          <p>0 1 0  0 2 0  0 3 0</p>
        </triangles>"##,
    );
    assert_eq!(s.triangles.len(), 1);
    assert_eq!(s.triangles[0].v, [1, 2, 3]);
    assert_eq!(s.triangles[0].n, Some([0, 0, 0]));
}

#[test]
fn polygons_and_polylists_are_fan_triangulated() {
    let s = load_geometry(
        r##"<polygons material="grey-sym" count="1">
          <input semantic="VERTEX" source="#g-vtx" offset="0"/>
          <p>0 1 2 3</p>
        </polygons>"##,
    );
    let v: Vec<_> = s.triangles.iter().map(|t| t.v).collect();
    assert_eq!(v, [[0, 1, 2], [0, 2, 3]]);
    let s = load_geometry(
        r##"<polylist material="grey-sym" count="2">
          <input semantic="VERTEX" source="#g-vtx" offset="0"/>
          <vcount>5 3</vcount>
          <p>4 0 1 2 3  0 1 2</p>
        </polylist>"##,
    );
    let v: Vec<_> = s.triangles.iter().map(|t| t.v).collect();
    assert_eq!(v, [[4, 0, 1], [4, 1, 2], [4, 2, 3], [0, 1, 2]]);
}

#[test]
fn triangles_are_wound_toward_their_corner_normals() {
    // Counter-clockwise about +z, but the file's normals say −z: corners 1 and 2 swap.
    let s = load_geometry(
        r##"<triangles material="grey-sym" count="1">
          <input semantic="VERTEX" source="#g-vtx" offset="0"/>
          <input semantic="NORMAL" source="#g-nrm" offset="1"/>
          <p>0 1 1 1 2 1</p>
        </triangles>"##,
    );
    assert_eq!(s.triangles[0].v, [0, 2, 1]);
    let [p0, p1, p2] = s.triangle_positions(0);
    assert!((p1 - p0).cross(p2 - p0).z < 0.0);
    // Without normals the file's winding is kept.
    let s = load_geometry(
        r##"<triangles material="grey-sym" count="1">
          <input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 2</p>
        </triangles>"##,
    );
    assert_eq!(s.triangles[0].v, [0, 1, 2]);
    assert_eq!(s.triangles[0].n, None);
}

#[test]
fn normals_use_the_inverse_transpose() {
    let nrm = r##"<library_geometries><geometry id="tilted"><mesh>
      <source id="t-pos"><float_array id="t-pos-a" count="9">0 0 0 1 -1 0 0 0 1</float_array></source>
      <source id="t-nrm"><float_array id="t-nrm-a" count="3">1 1 0</float_array></source>
      <vertices id="t-vtx"><input semantic="POSITION" source="#t-pos"/><input semantic="NORMAL" source="#t-nrm"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#t-vtx" offset="0"/><p>0 0 0</p></triangles>
    </mesh></geometry></library_geometries>"##;
    let nodes = format!(
        "<node><scale>1 2 1</scale>{}</node>",
        geometry_instance("tilted", "x", "grey")
    );
    let s = parse_ok(&scene_doc("Y_UP", nrm, &nodes));
    // Normals inside <vertices> share the position index; (1,1,0) under
    // diag(1,2,1)^{-T} = diag(1,½,1) is (1,½,0), normalized.
    let n = s.normals[0];
    assert!(close(n, Vec3::new(1.0, 0.5, 0.0).normalize()), "{n}");
    assert_eq!(s.triangles[0].n, Some([0, 0, 0]));
}

#[test]
fn instances_keep_document_order_and_area_quads_come_last() {
    let nodes = format!(
        r##"<node><instance_light url="#panel"/></node>
            <node><translate>10 0 0</translate>{q}</node>
            <node><translate>20 0 0</translate>{q}</node>"##,
        q = quad_instance()
    );
    let s = parse_ok(&scene_doc("Y_UP", PANEL, &nodes));
    assert_eq!(s.triangles.len(), 6);
    assert_eq!(s.triangle_positions(0)[0].x, 10.0);
    assert_eq!(s.triangle_positions(2)[0].x, 20.0);
    assert!(s.triangles[4..].iter().all(|t| t.light == 0));
}

const PANEL: &str = r##"<library_lights><light id="panel">
  <technique_common><directional><color>1 1 1</color></directional></technique_common>
  <extra><technique profile="blender"><area/></technique><technique profile="CMU462"><area><color>4 5 6</color></area></technique></extra>
</light></library_lights>"##;

#[test]
fn area_light_geometry_and_bounds() {
    let nodes = format!(
        r##"<node><translate>0 9 0</translate><scale>2 -3 1</scale><instance_light url="#panel"/></node>
            <node>{}</node>"##,
        quad_instance()
    );
    let s = parse_ok(&scene_doc("Y_UP", PANEL, &nodes));
    let Light::Area(AreaLight {
        centre,
        ex,
        ey,
        normal,
        radiance,
    }) = s.lights[0]
    else {
        panic!("{:?}", s.lights[0]);
    };
    let area = s.lights[0].as_area().expect("area light").area();
    assert_eq!(
        radiance,
        Vec3::new(4.0, 5.0, 6.0),
        "CMU462 extension over technique_common"
    );
    assert!(close(centre, Vec3::new(0.0, 9.0, 0.0)));
    assert!(close(ex, Vec3::new(2.0, 0.0, 0.0)) && close(ey, Vec3::new(0.0, -3.0, 0.0)));
    assert!((area - 6.0).abs() < 1e-5);
    // The node's local −Z is world −Z whatever the mirrored y axis does.
    assert!(close(normal, Vec3::NEG_Z), "{normal}");
    // The quad at y = 9 lies outside the bounds, which hold only the mesh.
    assert!(s.bounds.max.y <= 1.0, "{:?}", s.bounds);
}

#[test]
fn light_type_selection() {
    let lights = r##"<library_lights>
      <light id="odd"><technique_common><ambient><color>1 1 1</color></ambient></technique_common>
        <extra><technique profile="CGL"><foo/><point><color>9 9 9</color></point></technique></extra></light>
      <light id="sun"><technique_common><directional><color>2 2 2</color></directional></technique_common></light>
      <light id="spot"><technique_common><spot><color>2 2 2</color></spot></technique_common></light>
    </library_lights>"##;
    let nodes = r##"<node><translate>5 5 5</translate><rotate>1 0 0 -90</rotate>
        <instance_light url="#odd"/><instance_light url="#sun"/><instance_light url="#spot"/></node>"##;
    let s = parse_ok(&scene_doc("Y_UP", lights, nodes));
    // The extension's first element is not a light type, so technique_common decides;
    // an ambient light ignores its transform.
    assert_eq!(
        s.lights[0],
        Light::Ambient {
            radiance: Vec3::ONE
        }
    );
    // Local −Z rotated −90° about x points down; the translation is ignored.
    let Light::Directional {
        direction,
        irradiance,
    } = s.lights[1]
    else {
        panic!("{:?}", s.lights[1]);
    };
    assert!(close(direction, Vec3::NEG_Y), "{direction}");
    assert_eq!(irradiance, Vec3::splat(2.0));
    // Spot lights are read (tests/loader_exporters.rs checks their parameters).
    assert_eq!(s.lights.len(), 3);
    assert!(matches!(s.lights[2], Light::Spot(_)));
}

/// Materials of effects with the given CGL-extension bodies, in order.
fn materials_of(extensions: &[&str]) -> Vec<Material> {
    let mut libs = String::from("<library_effects>");
    for (i, body) in extensions.iter().enumerate() {
        libs += &format!(r#"<effect id="fx{i}"><extra>{body}</extra></effect>"#);
    }
    libs += "</library_effects><library_materials>";
    let mut nodes = String::new();
    for i in 0..extensions.len() {
        libs += &format!(r##"<material id="m{i}"><instance_effect url="#fx{i}"/></material>"##);
        nodes += &format!(
            "<node>{}</node>",
            geometry_instance("ball", "s", &format!("m{i}"))
        );
    }
    libs += "</library_materials>";
    let s = parse_ok(&scene_doc("Y_UP", &libs, &nodes));
    s.spheres
        .iter()
        .map(|sp| s.materials[sp.material as usize])
        .collect()
}

#[test]
fn material_kind_selection() {
    let got = materials_of(&[
        // The last kind wins.
        r#"<technique profile="CGL"><mirror><reflectance>1 1 1</reflectance></mirror>
           <glass><ior>1.3</ior><reflectance>1 1 1</reflectance><transmittance>0.5 0.5 0.5</transmittance><roughness>0</roughness></glass></technique>"#,
        // Only the first CGL/CMU462 technique counts; other profiles are skipped.
        r#"<technique profile="blender"><mirror><reflectance>1 0 0</reflectance></mirror></technique>
           <technique profile="CMU462"><refraction><ior>1.2</ior><transmittance>1 1 1</transmittance><roughness>0</roughness></refraction></technique>
           <technique profile="CGL"><mirror><reflectance>0 1 0</reflectance></mirror></technique>"#,
        r#"<technique profile="CGL"><microfacet><alpha>0.1</alpha><eta>1 2 3</eta><k>4 5 6</k></microfacet></technique>"#,
        r#"<technique profile="CGL"><emission><radiance>7 8 9</radiance></emission></technique>"#,
        // No extension kind: the default grey.
        r#"<technique profile="CGL"><sphere/></technique>"#,
    ]);
    assert_eq!(
        got,
        [
            Material::glass(1.3, Vec3::ONE, Vec3::splat(0.5)),
            Material::refraction(1.2, Vec3::ONE),
            Material::microfacet(0.1, Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)),
            Material::emitter(Vec3::new(7.0, 8.0, 9.0)),
            Material::lambertian(Vec3::splat(0.5)),
        ]
    );
}

#[test]
fn material_binding_falls_back_to_the_first_instance_material() {
    let nodes = r##"<node><instance_geometry url="#quad"><bind_material><technique_common>
              <instance_material symbol="other" target="#chrome"/>
              <instance_material symbol="more" target="#grey"/>
            </technique_common></bind_material></instance_geometry></node>"##;
    let s = parse_ok(&scene_doc("Y_UP", "", nodes));
    let m = s.materials[s.triangles[0].material as usize];
    assert!(matches!(m.bsdf, ember::materials::Bsdf::Mirror(_)), "{m:?}");
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("\"grey-sym\" is not bound")),
        "{:?}",
        s.warnings
    );
    // A material used twice is stored once.
    let nodes = format!("<node>{q}</node><node>{q}</node>", q = quad_instance());
    let s = parse_ok(&scene_doc("Y_UP", "", &nodes));
    assert_eq!(s.materials.len(), 1);
}

#[test]
fn sphere_centre_radius_and_non_uniform_scale() {
    let nodes = format!(
        "<node><translate>1 2 3</translate><scale>3 3 3</scale>{}</node>",
        geometry_instance("ball", "chrome", "chrome")
    );
    let s = parse_ok(&scene_doc("Y_UP", "", &nodes));
    assert!(close(s.spheres[0].centre, Vec3::new(1.0, 2.0, 3.0)));
    assert!((s.spheres[0].radius - 1.5).abs() < 1e-6);
    assert!(
        close(s.bounds.min, Vec3::new(-0.5, 0.5, 1.5))
            && close(s.bounds.max, Vec3::new(2.5, 3.5, 4.5))
    );
    assert!(
        !s.warnings.iter().any(|w| w.contains("scale")),
        "{:?}",
        s.warnings
    );
    let nodes = format!(
        "<node><scale>2 1 1</scale>{}</node>",
        geometry_instance("ball", "c", "chrome")
    );
    let s = parse_ok(&scene_doc("Y_UP", "", &nodes));
    assert!(
        (s.spheres[0].radius - 1.0).abs() < 1e-6,
        "the x scale is used"
    );
    assert!(
        s.warnings.iter().any(|w| w.contains("non-uniform scale")),
        "{:?}",
        s.warnings
    );
}

fn camera_doc(perspective: &str, transforms: &str) -> Scene {
    let libs = format!(
        r#"<library_cameras><camera id="c2"><optics><technique_common><perspective>{perspective}</perspective></technique_common></optics></camera></library_cameras>"#
    );
    let nodes = format!(
        r##"<node><instance_camera url="#cam"/></node><node>{transforms}<instance_camera url="#c2"/></node>"##
    );
    parse_ok(&scene_doc("Y_UP", &libs, &nodes))
}

#[test]
fn camera_field_of_view_rules() {
    let t = |deg: f32| (deg.to_radians() / 2.0).tan();
    // The last camera wins; yfov with aspect gives xfov.
    let c = camera_doc("<yfov>30</yfov><aspect_ratio>2</aspect_ratio>", "").camera;
    assert!((c.tan_half_y.unwrap() - t(30.0)).abs() < 1e-6);
    assert!((c.tan_half_x.unwrap() - 2.0 * t(30.0)).abs() < 1e-6);
    let c = camera_doc("<yfov>30</yfov>", "").camera;
    assert_eq!(c.tan_half_x, None);
    // SketchUp's and Assimp's aspect ratio 0 means "not given": one warning.
    let s = camera_doc("<xfov>60</xfov><aspect_ratio>0</aspect_ratio>", "");
    assert!((s.camera.tan_half_x.unwrap() - t(60.0)).abs() < 1e-6);
    assert_eq!(s.camera.tan_half_y, None);
    let zero = s.warnings.iter().filter(|w| w.contains("aspect ratio 0"));
    assert_eq!(zero.count(), 1, "{:?}", s.warnings);
    let c = camera_doc(
        "<xfov>50</xfov><yfov>20</yfov><aspect_ratio>9</aspect_ratio>",
        "",
    )
    .camera;
    assert!((c.tan_half_x.unwrap() - t(50.0)).abs() < 1e-6);
    assert!((c.tan_half_y.unwrap() - t(20.0)).abs() < 1e-6);
}

#[test]
fn camera_orientation_rules() {
    // Rolled 30° about the view axis: the roll is dropped, up stays world +Y.
    let c = camera_doc("<xfov>40</xfov>", "<rotate>0 0 1 30</rotate>").camera;
    assert!(
        close(c.forward, Vec3::NEG_Z) && close(c.up, Vec3::Y),
        "{c:?}"
    );
    // Tilted 20° up: up is +Y made orthogonal to the forward direction.
    let c = camera_doc("<xfov>40</xfov>", "<rotate>1 0 0 20</rotate>").camera;
    let a = 20f32.to_radians();
    assert!(close(c.forward, Vec3::new(0.0, a.sin(), -a.cos())), "{c:?}");
    assert!(close(c.up, Vec3::new(0.0, a.cos(), a.sin())), "{c:?}");
    // Looking straight down: up is the camera's own local +Y.
    let c = camera_doc("<xfov>40</xfov>", "<rotate>1 0 0 -90</rotate>").camera;
    assert!(
        close(c.forward, Vec3::NEG_Y) && close(c.up, Vec3::NEG_Z),
        "{c:?}"
    );
}

#[test]
fn geometry_instanced_twice_is_placed_twice() {
    let nodes = format!(
        "<node>{q}</node><node><translate>0 0 4</translate>{q}</node>",
        q = quad_instance()
    );
    let s = parse_ok(&scene_doc("Y_UP", "", &nodes));
    assert_eq!(s.triangles.len(), 4);
    assert_eq!(s.triangle_positions(3)[0].z, 4.0);
    assert_eq!(s.bounds.max.z, 4.0);
}
