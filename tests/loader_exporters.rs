//! What files from modelling tools other than the course's Blender bring (issue 26):
//! strips and fans, polygons with holes, lines, instanced nodes, decimal commas, zero
//! rotation axes, dangling bindings, UTF-16, `.zae` archives, the file's own camera,
//! emission, specular warnings, textures and spot lights (skinned meshes: loader_skins.rs).

use crate::common;

use common::{
    close, count_warnings, edit, edit_doc, geometry_instance, parse_err, parse_ok, quad_instance,
    scene_doc, TEMPLATE,
};
use ember::camera::Camera;
use ember::info::scene_info;
use ember::lights::Light;
use ember::materials::{Bsdf, Material};
use ember::scene::collada::{load, parse};
use ember::scene::{Placement, Scene};
use ember::Vec3;
use std::io::Write;
use std::path::Path;

/// A geometry `id` over the positions of a 3×3 grid in the z = 0 plane
/// (index `3·row + column`, at `(column, row, 0)`) whose only primitive is `prim`.
fn grid_geometry(id: &str, prim: &str) -> String {
    let mut pos = String::new();
    for r in 0..3 {
        for c in 0..3 {
            pos += &format!("{c} {r} 0 ");
        }
    }
    format!(
        r##"<library_geometries><geometry id="{id}"><mesh>
          <source id="{id}-pos"><float_array id="{id}-pos-a" count="27">{pos}</float_array></source>
          <vertices id="{id}-vtx"><input semantic="POSITION" source="#{id}-pos"/></vertices>
          {prim}
        </mesh></geometry></library_geometries>"##
    )
}

fn load_grid(prim: &str) -> Scene {
    let nodes = format!(
        "<node>{}</node>",
        geometry_instance("g", "grey-sym", "grey")
    );
    parse_ok(&scene_doc("Y_UP", &grid_geometry("g", prim), &nodes))
}

/// The error `prim` gives (one line, naming the file), which must hold `needles`.
fn load_grid_err(prim: &str, needles: &[&str]) -> String {
    let nodes = format!(
        "<node>{}</node>",
        geometry_instance("g", "grey-sym", "grey")
    );
    parse_err(
        &scene_doc("Y_UP", &grid_geometry("g", prim), &nodes),
        needles,
    )
}

fn area(s: &Scene) -> f32 {
    (0..s.triangles.len())
        .map(|i| {
            let [a, b, c] = s.triangle_positions(i);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// Whether triangle `i` covers point `q` of its plane (strictly inside).
fn covers(s: &Scene, i: usize, q: Vec3) -> bool {
    let [a, b, c] = s.triangle_positions(i);
    let n = (b - a).cross(c - a);
    [(a, b), (b, c), (c, a)]
        .iter()
        .all(|(p, r)| (*r - *p).cross(q - *p).dot(n) > 0.0)
}

/// Signed z of each triangle's geometric normal.
fn normal_z(s: &Scene) -> Vec<f32> {
    (0..s.triangles.len())
        .map(|i| {
            let [a, b, c] = s.triangle_positions(i);
            (b - a).cross(c - a).z
        })
        .collect()
}

#[test]
fn tristrips_and_trifans_are_triangulated() {
    // A strip 0 3 1 4 2 5 over the grid's two lower rows: four triangles, area 2.
    let s = load_grid(
        r##"<tristrips material="grey-sym" count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
             <p>0 3 1 4 2 5</p></tristrips>"##,
    );
    assert_eq!(s.triangles.len(), 4);
    assert!((area(&s) - 2.0).abs() < 1e-6, "{}", area(&s));
    // Every second triangle is flipped back, so the strip keeps one winding.
    let z = normal_z(&s);
    assert!(
        z.iter().all(|&v| v < 0.0) || z.iter().all(|&v| v > 0.0),
        "{z:?}"
    );
    // A fan around the centre 4 over five outer corners, and a stub of two corners.
    let s = load_grid(
        r##"<trifans material="grey-sym" count="2"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
             <p>4 0 1 2 5 8</p><p>0 1</p></trifans>"##,
    );
    assert_eq!(s.triangles.len(), 4);
    assert!((area(&s) - 2.0).abs() < 1e-6);
    // The stub is skipped with a warning naming the element (the other warning:
    // scene_doc's scene has no camera).
    assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);
    let stub = "<geometry id=\"g\">/mesh/trifans: a face of fewer than 3 corners makes no triangle; skipped";
    assert!(
        s.warnings.iter().any(|w| w.ends_with(stub)),
        "{:?}",
        s.warnings
    );
    // Once per file, however many stubs.
    let s = load_grid(
        r##"<tristrips material="grey-sym" count="3"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
             <p>0 1</p><p>0 3 1</p><p>4</p></tristrips>"##,
    );
    assert_eq!(s.triangles.len(), 1);
    let stubs = s
        .warnings
        .iter()
        .filter(|w| w.contains("fewer than 3 corners"));
    assert_eq!(stubs.count(), 1, "{:?}", s.warnings);
}

/// FBX and OpenCOLLADA exports carry faces of two corners (and `vcount` zeros) where
/// the source mesh had loose edges: the face is skipped with one warning, the rest
/// of the primitive loads.
#[test]
fn faces_of_fewer_than_three_corners_are_skipped_with_one_warning() {
    let short = |s: &ember::scene::Scene| {
        s.warnings
            .iter()
            .filter(|w| w.contains("fewer than 3 corners"))
            .count()
    };
    let s = load_grid(
        r##"<polylist material="grey-sym" count="4"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
             <vcount>4 2 0 3</vcount><p>0 1 4 3  1 2  4 5 8</p></polylist>"##,
    );
    assert_eq!(s.triangles.len(), 3);
    assert!((area(&s) - 1.5).abs() < 1e-6, "{}", area(&s));
    assert_eq!(short(&s), 1, "{:?}", s.warnings);
    let s = load_grid(
        r##"<polygons material="grey-sym" count="3"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
             <p>0 1 4 3</p><p>1 2</p><ph><p>4 5</p><h>0 1 2</h></ph></polygons>"##,
    );
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(short(&s), 1, "{:?}", s.warnings);
    // A corner cut in half is still an error, naming the element.
    load_grid_err(
        r##"<polylist material="grey-sym" count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
             <input semantic="TEXTANGENT" source="#g-vtx" offset="1"/>
             <vcount>3</vcount><p>0 0 1 1 4</p></polylist>"##,
        &["polylist/vcount", "<p> has 5 indices"],
    );
}

/// COLLADA gives `<triangles>` one `<p>`; exporters that write one per batch of
/// faces lose none of them, with one warning, and `count` covers all of them.
#[test]
fn triangles_with_several_p_are_all_read() {
    let prim = |count: &str| {
        format!(
            r##"<triangles material="grey-sym"{count}><input semantic="VERTEX" source="#g-vtx" offset="0"/>
             <p>0 1 4  0 4 3</p><p>1 2 5</p><p>1 5 4</p></triangles>"##
        )
    };
    for count in ["", " count=\"4\""] {
        let s = load_grid(&prim(count));
        assert_eq!(s.triangles.len(), 4, "{count}");
        assert!((area(&s) - 2.0).abs() < 1e-6, "{}", area(&s));
        let several = s.warnings.iter().filter(|w| w.contains("several <p>"));
        assert_eq!(several.count(), 1, "{:?}", s.warnings);
    }
    load_grid_err(
        &prim(" count=\"2\""),
        &["triangles", "count is 2 but 4 faces"],
    );
}

#[test]
fn polygons_with_holes_are_triangulated_around_the_hole() {
    // The outer square 0 2 8 6 (area 4) with a square hole [0.5, 1.5]² around its centre.
    let prim = r##"<polygons material="grey-sym" count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
        <ph><p>0 2 8 6</p><h>9 10 11 12</h></ph></polygons>"##;
    let mut doc = scene_doc(
        "Y_UP",
        &grid_geometry("g", prim),
        &format!(
            "<node>{}</node>",
            geometry_instance("g", "grey-sym", "grey")
        ),
    );
    // Four more positions: the square [0.5, 1.5]² (indices 9–12).
    doc = doc.replace(
        "count=\"27\">",
        "count=\"39\">0.5 0.5 0 1.5 0.5 0 1.5 1.5 0 0.5 1.5 0 ",
    );
    // The extra positions were put first: shift the grid's indices by 4 in <p>, and
    // the hole is 0 1 2 3.
    let doc = doc
        .replace("<p>0 2 8 6</p>", "<p>4 6 12 10</p>")
        .replace("<h>9 10 11 12</h>", "<h>0 1 2 3</h>");
    let s = parse_ok(&doc);
    // 4 + 4 corners and two bridge corners: 8 triangles covering 4 − 1.
    assert_eq!(s.triangles.len(), 8);
    assert!((area(&s) - 3.0).abs() < 1e-5, "area {}", area(&s));
    for i in 0..s.triangles.len() {
        assert!(
            !covers(&s, i, Vec3::new(1.0, 1.0, 0.0)),
            "triangle {i} covers the hole"
        );
    }
}

#[test]
fn lines_are_skipped_with_one_warning() {
    let lines = r##"<lines count="2"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 1 2</p></lines>
        <linestrips count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 2</p></linestrips>
        <triangles material="grey-sym" count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 4</p></triangles>"##;
    let s = load_grid(lines);
    assert_eq!(s.triangles.len(), 1);
    let w: Vec<_> = s.warnings.iter().filter(|w| w.contains("lines")).collect();
    assert_eq!(w.len(), 1, "{:?}", s.warnings);
}

#[test]
fn instance_node_places_library_nodes() {
    let libs = format!(
        r##"<library_nodes><node id="unit">{}</node>
             <node id="pair"><instance_node url="#unit"/><node><translate>5 0 0</translate><instance_node url="#unit"/></node></node>
           </library_nodes>"##,
        quad_instance()
    );
    let nodes = r##"<node><translate>0 10 0</translate><instance_node url="#pair"/></node>
                    <node><instance_node url="#nothing"/></node>"##;
    let s = parse_ok(&scene_doc("Y_UP", &libs, nodes));
    assert_eq!(s.triangles.len(), 4);
    assert!(
        close(s.positions[1], Vec3::new(1.0, 10.0, 0.0)),
        "{}",
        s.positions[1]
    );
    assert!(close(s.positions[4 + 1], Vec3::new(6.0, 10.0, 0.0)));
    assert!(s
        .warnings
        .iter()
        .any(|w| w.contains("instance_node") && w.contains("#nothing")));
    // A node instancing itself ends in an error, not a hang or a stack overflow.
    let libs =
        r##"<library_nodes><node id="loop"><instance_node url="#loop"/></node></library_nodes>"##;
    parse_err(
        &scene_doc(
            "Y_UP",
            libs,
            r##"<node><instance_node url="#loop"/></node>"##,
        ),
        &["deeper than"],
    );
}

/// The template with every decimal point written as a comma.
fn comma_template() -> String {
    let mut out = String::new();
    let mut in_tag = false;
    let chars: Vec<char> = TEMPLATE.chars().collect();
    for (i, &c) in chars.iter().enumerate() {
        match c {
            '<' => in_tag = true,
            '>' => in_tag = false,
            _ => {}
        }
        let digit = |k: usize| chars.get(k).is_some_and(|d| d.is_ascii_digit());
        if c == '.' && !in_tag && i > 0 && digit(i - 1) && digit(i + 1) {
            out.push(',');
        } else {
            out.push(c);
        }
    }
    out
}

#[test]
fn decimal_commas_load_with_one_warning() {
    let doc = comma_template();
    assert!(doc.contains("0,3 0,3 0,3"));
    let s = parse_ok(&doc);
    let reference = parse_ok(TEMPLATE);
    assert_eq!(s.materials, reference.materials);
    assert_eq!(s.spheres, reference.spheres);
    let w: Vec<_> = s
        .warnings
        .iter()
        .filter(|w| w.contains("decimal comma"))
        .collect();
    assert_eq!(w.len(), 1, "{:?}", s.warnings);
    // Mixed with decimal points, a comma is ambiguous: an error.
    let mixed = doc.replacen(
        "<translate>0 0 1</translate>",
        "<translate>0 0 1.5</translate>",
        1,
    );
    parse_err(&mixed, &["is not a finite number"]);
}

#[test]
fn a_zero_rotation_axis_is_the_identity_with_a_warning() {
    // Animation exporters write one per node: one warning for the file.
    let doc = edit(
        "<translate>0 0 1</translate>",
        "<translate>0 0 1</translate><rotate>0 0 0 0</rotate>",
    )
    .replace(
        "<translate>0 0 3</translate>",
        "<translate>0 0 3</translate><rotate>0 0 0 0</rotate>",
    );
    let s = parse_ok(&doc);
    let reference = parse_ok(TEMPLATE);
    assert_eq!(s.spheres, reference.spheres);
    assert_eq!(s.lights, reference.lights);
    let w: Vec<_> = s.warnings.iter().filter(|w| w.contains("zero")).collect();
    assert_eq!(w.len(), 1, "{:?}", s.warnings);
    assert!(w[0].starts_with("scene.dae: <node id=\"ball-node\">/rotate"));
}

#[test]
fn a_dangling_material_binding_falls_back_with_a_warning() {
    // A target naming nothing, or something in another file, loses only the material.
    for target in ["#nothing", "materials.dae#grey"] {
        let s = parse_ok(&edit("target=\"#grey\"", &format!("target=\"{target}\"")));
        assert_eq!(s.triangles.len(), 2);
        assert_eq!(
            s.materials[s.triangles[0].material as usize],
            Material::default()
        );
        assert!(s.warnings.iter().any(|w| w.starts_with("scene.dae: ")
            && w.contains("instance_material")
            && w.contains(target)));
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn utf16_and_byte_order_marks_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let reference = parse_ok(TEMPLATE);
    let text = TEMPLATE.replace("encoding=\"utf-8\"", "encoding=\"UTF-16\"");
    let le: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(text.encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    let be: Vec<u8> = [0xFE, 0xFF]
        .into_iter()
        .chain(text.encode_utf16().flat_map(u16::to_be_bytes))
        .collect();
    let bom8: Vec<u8> = [0xEF, 0xBB, 0xBF]
        .into_iter()
        .chain(TEMPLATE.bytes())
        .collect();
    // Without a mark, the opening `<` in UTF-16 tells the byte order (XML 1.0, appendix F).
    let le_bare = le[2..].to_vec();
    let be_bare = be[2..].to_vec();
    for (name, bytes) in [
        ("le.dae", le),
        ("be.dae", be),
        ("bom8.dae", bom8),
        ("le_bare.dae", le_bare),
        ("be_bare.dae", be_bare),
    ] {
        let s = load(&write(dir.path(), name, &bytes)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(s.positions, reference.positions, "{name}");
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
    }
    // An odd byte after the mark is not UTF-16: a one-line error.
    let p = write(dir.path(), "bad.dae", &[0xFF, 0xFE, 0x00, 0xD8, 0x41, 0x00]);
    let e = load(&p).unwrap_err().to_string();
    assert!(
        e.contains("bad.dae") && e.contains("UTF-16") && !e.contains('\n'),
        "{e}"
    );
}

fn zip_file(path: &Path, entries: &[(&str, &[u8])]) {
    let mut z = zip::ZipWriter::new(std::fs::File::create(path).unwrap());
    for (name, bytes) in entries {
        z.start_file(*name, zip::write::SimpleFileOptions::default())
            .unwrap();
        z.write_all(bytes).unwrap();
    }
    z.finish().unwrap();
}

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/collada");

#[test]
fn zae_archives_are_read_with_or_without_a_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let dae = std::fs::read(Path::new(DATA).join("textured_quad.dae")).unwrap();
    let png = std::fs::read(Path::new(DATA).join("texture4x4.png")).unwrap();
    let manifest = b"<?xml version=\"1.0\"?><dae_root>./models/quad.dae</dae_root>";
    let with = dir.path().join("with.zae");
    zip_file(
        &with,
        &[
            ("manifest.xml", manifest),
            ("models/quad.dae", &dae),
            ("models/texture4x4.png", &png),
            ("other.dae", b"not xml"),
        ],
    );
    let s = load(&with).unwrap_or_else(|e| panic!("{e}"));
    let direct = load(&Path::new(DATA).join("textured_quad.dae")).unwrap();
    assert_eq!(s.triangles.len(), direct.triangles.len());
    assert_eq!(s.textures.len(), 1);
    assert_eq!(s.textures[0].width(), 4);
    let without = dir.path().join("without.zae");
    zip_file(&without, &[("quad.dae", &dae), ("texture4x4.png", &png)]);
    assert_eq!(load(&without).unwrap().textures.len(), 1);
    // A manifest naming nothing, and a broken archive, are one-line errors.
    let bad = dir.path().join("bad.zae");
    zip_file(&bad, &[("manifest.xml", b"<dae_root>gone.dae</dae_root>")]);
    let e = load(&bad).unwrap_err().to_string();
    assert!(e.contains("bad.zae") && e.contains("dae_root"), "{e}");
    let truncated = write(dir.path(), "cut.zae", &std::fs::read(&with).unwrap()[..60]);
    let e = load(&truncated).unwrap_err().to_string();
    assert!(e.contains("cut.zae") && !e.contains('\n'), "{e}");
}

/// The template as `tool` would write it: without the course's CGL extension (its
/// sphere and mirror then load as an empty geometry and a grey material).
fn with_tool(tool: &str) -> String {
    edit(
        "<asset><up_axis>Z_UP</up_axis></asset>",
        &format!(
            "<asset><contributor><authoring_tool>{tool}</authoring_tool></contributor><up_axis>Z_UP</up_axis></asset>"
        ),
    )
    .replace("profile=\"CGL\"", "profile=\"OTHER\"")
}

#[test]
fn files_from_other_tools_keep_their_camera_position() {
    // The template's camera node stands at (0, −3, 1) in its Z_UP frame: (0, 1, −3) here.
    let maya = parse_ok(&with_tool("Maya 2020 | ColladaMaya v3.05B"));
    assert_eq!(maya.camera.placement, Placement::File);
    let cam = Camera::new(&maya.camera, &maya.bounds, 64, 48);
    assert!(close(cam.eye, Vec3::new(0.0, 1.0, -3.0)), "{}", cam.eye);
    let info = scene_info(&maya, 64, 48);
    assert!(
        info.contains("placement: the file's camera position"),
        "{info}"
    );
    assert!(info.contains("Maya 2020"), "{info}");
    // The course's exporter, and files naming no tool, keep the course's rule.
    for doc in [
        with_tool("Blender 2.74.0 commit date:2015-03-31, commit time:13:39, hash:000dfc0"),
        TEMPLATE.to_string(),
    ] {
        let s = parse_ok(&doc);
        assert_eq!(s.camera.placement, Placement::Course);
        let cam = Camera::new(&s.camera, &s.bounds, 64, 48);
        let rule = s.bounds.centre() - 1.5 * s.bounds.diagonal().length() * cam.forward;
        assert!(close(cam.eye, rule), "{}", cam.eye);
        assert!(scene_info(&s, 64, 48).contains("placement: course rule"));
    }
}

fn effect_doc(body: &str) -> String {
    edit(
        "<lambert>\n      <diffuse><color>0.3 0.3 0.3 1</color></diffuse>\n    </lambert>",
        body,
    )
}

#[test]
fn emission_makes_a_surface_emit() {
    let s = parse_ok(&effect_doc(
        "<lambert><emission><color>2 3 4 1</color></emission><diffuse><color>0 0 0 1</color></diffuse></lambert>",
    ));
    // It emits from its front, and reflects its (here black) diffuse colour too.
    assert_eq!(
        s.materials[s.triangles[0].material as usize],
        Material::lambertian(Vec3::ZERO).with_emission(Vec3::new(2.0, 3.0, 4.0), false)
    );
    assert!(s.has_unsampled_emitters());
    // Black emission is no emission.
    let s = parse_ok(&effect_doc(
        "<phong><emission><color>0 0 0 1</color></emission><diffuse><color>0.3 0.3 0.3 1</color></diffuse></phong>",
    ));
    let m = s.materials[s.triangles[0].material as usize];
    assert!(matches!(m.bsdf, Bsdf::Lambertian(_)) && !m.emits());
}

#[test]
fn specular_is_warned_about_once_per_material_outside_course_files() {
    let phong = "<phong><diffuse><color>0.3 0.3 0.3 1</color></diffuse>\
        <specular><color>0.5 0.5 0.5 1</color></specular><shininess><float>50</float></shininess></phong>";
    let doc = with_tool("3ds Max").replace(
        "<lambert>\n      <diffuse><color>0.3 0.3 0.3 1</color></diffuse>\n    </lambert>",
        phong,
    );
    // The quad instanced twice still gives one warning for its one material.
    let doc = doc.replace(
        "<node id=\"ball-node\">",
        &format!("<node>{}</node><node id=\"ball-node\">", quad_instance()),
    );
    let s = parse_ok(&doc);
    assert!(
        matches!(s.materials[0].bsdf, Bsdf::Lambertian(b) if b.albedo.vec3() == Vec3::splat(0.3))
    );
    let w: Vec<_> = s
        .warnings
        .iter()
        .filter(|w| w.contains("specular"))
        .collect();
    assert_eq!(w.len(), 1, "{:?}", s.warnings);
    // The course's files mean Lambertian by <phong> (spec §6): no warning there.
    let s = parse_ok(&effect_doc(phong));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

#[test]
fn spot_lights_are_read() {
    let s = load(&Path::new(DATA).join("spot_plane.dae")).unwrap();
    let [Light::Spot(spot)] = s.lights.as_slice() else {
        panic!("{:?}", s.lights);
    };
    assert!(close(spot.position, Vec3::Y));
    assert!(close(spot.direction, Vec3::NEG_Y));
    assert_eq!(spot.intensity, Vec3::splat(2.0));
    assert!((spot.cutoff_degrees() - 45.0).abs() < 1e-4);
    assert_eq!(spot.exponent, 2.0);
    assert!(scene_info(&s, 8, 8).contains("spot: intensity (2, 2, 2)"));
    // Defaults: a 180° cone without falloff.
    let libs = r##"<library_lights><light id="s"><technique_common><spot><color>1 1 1</color></spot></technique_common></light></library_lights>"##;
    let s = parse_ok(&scene_doc(
        "Y_UP",
        libs,
        r##"<node><instance_light url="#s"/></node>"##,
    ));
    let Light::Spot(spot) = s.lights[0] else {
        panic!()
    };
    assert!((spot.cutoff_degrees() - 90.0).abs() < 1e-4 && spot.exponent == 0.0);
    // A full angle past 360° (the whole sphere) is read as 360° with a warning; 300° is a cone.
    let spot_at = |angle: &str| {
        let libs = libs.replace(
            "</color>",
            &format!("</color><falloff_angle>{angle}</falloff_angle>"),
        );
        parse_ok(&scene_doc(
            "Y_UP",
            &libs,
            r##"<node><instance_light url="#s"/></node>"##,
        ))
    };
    let wide = spot_at("720");
    let Light::Spot(spot) = wide.lights[0] else {
        panic!()
    };
    assert_eq!(spot.cos_cutoff, -1.0);
    let warned: Vec<_> = (wide.warnings.iter())
        .filter(|w| w.contains("<light id=\"s\">/technique_common/spot/falloff_angle: 720 degrees"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", wide.warnings);
    let cone = spot_at("300");
    assert!(
        !cone.warnings.iter().any(|w| w.contains("falloff_angle")),
        "{:?}",
        cone.warnings
    );
}

#[test]
fn textures_bind_their_coordinate_set_and_are_listed() {
    let s = load(&Path::new(DATA).join("textured_quad.dae")).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.textures.len(), 1);
    let t = &s.textures[0];
    assert_eq!((t.width(), t.height()), (4, 4));
    assert_eq!(t.wrap_s, ember::texture::Wrap::Clamp);
    // Every corner reads set 0, (x + 1)/2, (1 − z)/2, not the decoy set 1.
    for (i, tri) in s.triangles.iter().enumerate() {
        let uv = s.triangle_uvs[i].expect("textured triangles carry coordinates");
        for (&v, &k) in tri.v.iter().zip(&uv) {
            let p = s.positions[v as usize];
            let want = ember::Vec2::new((p.x + 1.0) / 2.0, (1.0 - p.z) / 2.0);
            assert!((s.uvs[k as usize] - want).length() < 1e-6);
        }
    }
    let info = scene_info(&s, 8, 8);
    assert!(info.contains("textures: 1"), "{info}");
    assert!(
        info.contains("texture4x4.png: 4x4, wrap CLAMP/CLAMP"),
        "{info}"
    );
    // A binding naming a set the mesh lacks: the mesh's first set (here the decoy,
    // set 1), with one warning naming the binding.
    let text = std::fs::read_to_string(Path::new(DATA).join("textured_quad.dae")).unwrap();
    let bad = text.replace("input_set=\"0\"", "input_set=\"7\"");
    assert_ne!(bad, text);
    let s = parse_in_data(&bad);
    let warned: Vec<_> = (s.warnings.iter())
        .filter(|w| w.contains("<bind_vertex_input input_set=\"7\"> names a TEXCOORD set the mesh lacks; its set 1 is used"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", s.warnings);
    for uv in s.triangle_uvs.iter().flatten().flatten() {
        assert_eq!(s.uvs[*uv as usize], ember::Vec2::splat(0.5));
    }
    assert_eq!(s.triangle_uvs.iter().flatten().count(), s.triangles.len());
}

/// `doc` loaded from a file in the test data folder, where its images are.
fn parse_in_data(doc: &str) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "texture4x4.png",
        &std::fs::read(Path::new(DATA).join("texture4x4.png")).unwrap(),
    );
    load(&write(dir.path(), "scene.dae", doc.as_bytes())).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_missing_texture_is_an_error_unless_a_colour_stands_in() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(Path::new(DATA).join("textured_quad.dae")).unwrap();
    let gone = text.replace("texture4x4.png", "gone.png");
    let e = load(&write(dir.path(), "gone.dae", gone.as_bytes()))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("gone.dae") && e.contains("<image id=\"tex-image\">/init_from"),
        "{e}"
    );
    assert!(e.contains("gone.png") && !e.contains('\n'), "{e}");
    let with_colour = gone.replace(
        "<diffuse><texture",
        "<diffuse><color>0.2 0.4 0.6 1</color><texture",
    );
    let s = load(&write(dir.path(), "colour.dae", with_colour.as_bytes())).unwrap();
    assert!(s.textures.is_empty());
    assert!(
        matches!(s.materials[0].bsdf, Bsdf::Lambertian(b) if close(b.albedo.vec3(), Vec3::new(0.2, 0.4, 0.6)))
    );
    assert!(
        s.warnings.iter().any(|w| w.contains("gone.png")),
        "{:?}",
        s.warnings
    );
    // A file that is no image is reported the same way.
    write(dir.path(), "texture4x4.png", b"not a png");
    let e = load(&write(dir.path(), "junk.dae", text.as_bytes()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("texture4x4.png") && !e.contains('\n'), "{e}");
}

#[test]
fn parse_reads_images_relative_to_the_current_directory() {
    // `parse` has no file to be beside; a relative image then names nothing here.
    let text = std::fs::read_to_string(Path::new(DATA).join("textured_quad.dae")).unwrap();
    assert!(parse(&text, "quad.dae").is_err());
}

#[test]
fn off_standard_references_and_arrays_load_with_a_warning_naming_the_file() {
    // The file's own name before '#' is a local reference.
    let s = parse_ok(&edit(
        "<instance_geometry url=\"#quad\">",
        "<instance_geometry url=\"./scene.dae#quad\">",
    ));
    assert_eq!(s.triangles.len(), 2);
    // More numbers than a float_array's count: the accessor's are read, with a warning.
    let s = parse_ok(&edit(
        "count=\"12\">0 0 0 1 0 0 1 1 0 0 1 0</float_array>",
        "count=\"12\">0 0 0 1 0 0 1 1 0 0 1 0 7 7 7</float_array>",
    ));
    assert_eq!(s.positions, parse_ok(TEMPLATE).positions);
    assert!(s
        .warnings
        .iter()
        .any(|w| w.contains("extra ones are not read")));
    // Two-component positions lie in z = 0.
    let doc = edit(
        "count=\"12\">0 0 0 1 0 0 1 1 0 0 1 0</float_array>\n          <technique_common><accessor source=\"#quad-pos-array\" count=\"4\" stride=\"3\"/>",
        "count=\"8\">0 0 1 0 1 1 0 1</float_array>\n          <technique_common><accessor source=\"#quad-pos-array\" count=\"4\" stride=\"2\"/>",
    );
    let s = parse_ok(&doc);
    assert_eq!(s.positions, parse_ok(TEMPLATE).positions);
}

#[test]
fn concave_polygons_are_ear_clipped_and_convex_ones_fanned() {
    // An L of six corners over the grid, the notch [1, 2]² at the upper right, starting
    // at (1, 2), from where a fan would cover part of the notch.
    let s = load_grid(
        r##"<polylist material="grey-sym" count="2"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
             <vcount>6 4</vcount><p>7 6 0 2 5 4  0 1 4 3</p></polylist>"##,
    );
    assert_eq!(s.triangles.len(), 4 + 2);
    assert!((area(&s) - (3.0 + 1.0)).abs() < 1e-6, "{}", area(&s));
    // No triangle of the L reaches into the notch (the fan's (1,2) (2,0) (2,1) would).
    for i in 0..4 {
        assert!(
            !covers(&s, i, Vec3::new(1.4, 1.5, 0.0)),
            "triangle {i} covers the notch"
        );
    }
    // The convex quad keeps the fan (0, 1, 4), (0, 4, 3).
    let quad: Vec<_> = (4..6).map(|i| s.triangle_positions(i)).collect();
    assert!(
        close(quad[0][2], Vec3::new(1.0, 1.0, 0.0)) && close(quad[1][1], Vec3::new(1.0, 1.0, 0.0))
    );
}

/// Blender 2.80 and later export a point or spot light's colour times its power in
/// watts; the intensity that power gives is P/4π. Older Blender (the course's
/// exporter) and other tools keep the colour as the intensity; a sun is irradiance.
#[test]
fn blender_watts_become_intensity() {
    let point = |s: &Scene| match s.lights[0] {
        Light::Point { intensity, .. } => intensity,
        ref l => panic!("{l:?}"),
    };
    let four_pi = 4.0 * std::f32::consts::PI;
    for (tool, scale) in [
        ("Blender 2.80.75 commit date:2019-07-29", 1.0 / four_pi),
        ("Blender 4.5.1 LTS", 1.0 / four_pi),
        ("Blender 2.79.0 commit date:2017-09-11", 1.0),
        ("Blender 2.74.0 commit date:2015-03-31", 1.0),
        ("3ds Max", 1.0),
    ] {
        let s = parse_ok(&with_tool(tool));
        assert!(close(point(&s), Vec3::new(1.0, 2.0, 3.0) * scale), "{tool}");
        let warned = count_warnings(&s, "watts");
        assert_eq!(
            warned,
            usize::from(scale != 1.0),
            "{tool}: {:?}",
            s.warnings
        );
    }
    // With the course's extension the course's units stand, whichever Blender wrote it.
    let course = edit(
        "<asset><up_axis>Z_UP</up_axis></asset>",
        "<asset><contributor><authoring_tool>Blender 3.6.0</authoring_tool></contributor><up_axis>Z_UP</up_axis></asset>",
    );
    let s = parse_ok(&course);
    assert!(close(point(&s), Vec3::new(1.0, 2.0, 3.0)));
    assert_eq!(count_warnings(&s, "watts"), 0);
    let sun = with_tool("Blender 3.6.0").replace(
        "<point><color>1 2 3</color></point>",
        "<directional><color>1 2 3</color></directional>",
    );
    let s = parse_ok(&sun);
    assert!(
        matches!(s.lights[0], Light::Directional { irradiance, .. } if irradiance == Vec3::new(1.0, 2.0, 3.0))
    );
    assert_eq!(count_warnings(&s, "watts"), 0);
}

/// `url="#Cube%20mesh"` names `id="Cube mesh"`, as a URI fragment escapes a space.
#[test]
fn percent_escaped_references_are_decoded() {
    let doc = edit("<geometry id=\"quad\">", "<geometry id=\"quad mesh\">").replacen(
        "url=\"#quad\"",
        "url=\"#quad%20mesh\"",
        1,
    );
    let s = parse_ok(&doc);
    assert_eq!(s.triangles.len(), 2);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

/// Assimp writes `inf` for a spot light whose inner and outer cones are equal.
#[test]
fn an_infinite_spot_falloff_exponent_is_read_as_a_hard_edge() {
    let doc = edit(
        "<point><color>1 2 3</color></point>",
        "<spot><color>1 2 3</color><falloff_angle>60</falloff_angle><falloff_exponent>inf</falloff_exponent></spot>",
    );
    let s = parse_ok(&doc);
    assert!(matches!(s.lights[0], Light::Spot(_)));
    assert_eq!(
        count_warnings(&s, "infinite falloff exponent"),
        1,
        "{:?}",
        s.warnings
    );
    let nan = doc.replace(">inf<", ">nan<");
    parse_err(&nan, &["falloff_exponent", "nan"]);
}

#[test]
fn common_profile_colours_by_reference_constant_shading_and_vertex_colours() {
    // <diffuse><param ref> names a <newparam> holding the colour (the spec's own example).
    let s = parse_ok(&effect_doc(
        "<lambert><diffuse><param ref=\"base\"/></diffuse></lambert>",
    ).replace(
        "<technique sid=\"common\">",
        "<newparam sid=\"base\"><float4>0.2 0.4 0.6 1</float4></newparam><technique sid=\"common\">",
    ));
    let m = s.materials[s.triangles[0].material as usize];
    assert!(
        matches!(m.bsdf, Bsdf::Lambertian(b) if close(b.albedo.vec3(), Vec3::new(0.2, 0.4, 0.6))),
        "{m:?}"
    );
    // A reference to nothing: the default colour, with a warning naming it.
    let s = parse_ok(&effect_doc(
        "<lambert><diffuse><param ref=\"nowhere\"/></diffuse></lambert>",
    ));
    assert_eq!(count_warnings(&s, "ref=\"nowhere\""), 1, "{:?}", s.warnings);
    // <constant> is unlit: its emission alone, no reflection.
    let s = parse_ok(&effect_doc(
        "<constant><emission><color>1 0 0 1</color></emission></constant>",
    ));
    let m = s.materials[s.triangles[0].material as usize];
    assert!(m.emits());
    assert!(matches!(m.bsdf, Bsdf::Lambertian(b) if b.albedo.vec3() == Vec3::ZERO));
    // Vertex colours are not read: one warning however many primitives carry them.
    let colour = "<input semantic=\"COLOR\" source=\"#quad-nrm\" offset=\"1\"/>";
    let doc = edit(
        "<input semantic=\"NORMAL\" source=\"#quad-nrm\" offset=\"1\"/>",
        &format!("<input semantic=\"NORMAL\" source=\"#quad-nrm\" offset=\"1\"/>{colour}"),
    );
    let s = parse_ok(&doc);
    assert_eq!(count_warnings(&s, "vertex colours"), 1, "{:?}", s.warnings);
}

/// Reflectances are checked: a negative colour is an error naming the element, one
/// above 1 (energy from nowhere, or a colour written 0-255) a warning.
#[test]
fn negative_colours_are_errors_and_gains_are_warned() {
    parse_err(
        &edit("<color>1 2 3</color>", "<color>-8 8 8</color>"),
        &["point/color", "-8 is negative"],
    );
    parse_err(
        &effect_doc("<lambert><diffuse><color>-0.7 0.3 0.3 1</color></diffuse></lambert>"),
        &["diffuse/color", "negative"],
    );
    parse_err(
        &edit(
            "<reflectance>0.9 0.9 0.9</reflectance>",
            "<reflectance>-1 0.9 0.9</reflectance>",
        ),
        &["mirror/reflectance", "negative"],
    );
    let s = parse_ok(&effect_doc(
        "<lambert><diffuse><color>7 0.3 0.3 1</color></diffuse></lambert>",
    ));
    assert_eq!(count_warnings(&s, "above 1"), 1, "{:?}", s.warnings);
}

/// A bare `<!DOCTYPE COLLADA>` defines no entities: read past with one warning. One
/// with an internal subset could expand without bound: an error.
#[test]
fn a_bare_doctype_loads_with_a_warning() {
    let doc = TEMPLATE.replacen("<COLLADA ", "<!DOCTYPE COLLADA>\n<COLLADA ", 1);
    let s = parse_ok(&doc);
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(count_warnings(&s, "DOCTYPE"), 1, "{:?}", s.warnings);
    let bomb = TEMPLATE.replacen(
        "<COLLADA ",
        "<!DOCTYPE COLLADA [<!ENTITY a \"aaaa\"><!ENTITY b \"&a;&a;&a;\">]>\n<COLLADA ",
        1,
    );
    parse_err(&bomb, &["DOCTYPE", "internal subset"]);
}

/// A VERTEX input naming the positions' `<source>` directly (some writers skip
/// `<vertices>`) reads them, with one warning.
#[test]
fn vertex_input_naming_a_source_reads_its_positions() {
    let doc = edit(
        "<input semantic=\"VERTEX\" source=\"#quad-vtx\" offset=\"0\"/>",
        "<input semantic=\"VERTEX\" source=\"#quad-pos\" offset=\"0\"/>",
    );
    let s = parse_ok(&doc);
    assert_eq!(s.triangles.len(), 2);
    assert!((area(&s) - 1.0).abs() < 1e-6);
    assert_eq!(
        count_warnings(&s, "VERTEX names a <source>"),
        1,
        "{:?}",
        s.warnings
    );
}

/// Coordinates beyond ±1e18 overflow the BVH's `f32` areas: an error naming the node,
/// not a panic. A transform that flattens a whole mesh to nothing is said once.
#[test]
fn huge_and_flattened_placements() {
    let huge = edit(
        "<matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix>",
        "<scale>1e20 1e20 1e20</scale>",
    );
    parse_err(&huge, &["<node id=\"quad-node\">", "beyond"]);
    let huge_ball = edit(
        "<translate>0 0 1</translate>",
        "<scale>1e38 1e38 1e38</scale>",
    );
    parse_err(&huge_ball, &["<node id=\"ball-node\">", "beyond"]);
    let flat = edit(
        "<matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix>",
        "<scale>0 0 0</scale>",
    );
    let s = parse_ok(&flat);
    assert_eq!(count_warnings(&s, "zero area"), 1, "{:?}", s.warnings);
    // Flattening a mesh along the axis it already lies flat on changes nothing.
    let s = parse_ok(&edit(
        "<matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix>",
        "<scale>1 1 0</scale>",
    ));
    assert_eq!(count_warnings(&s, "zero area"), 0, "{:?}", s.warnings);
}

/// An `<instance_camera>` naming nothing is one problem: one warning, which says
/// what the render does instead.
#[test]
fn a_dangling_camera_gives_one_warning() {
    let s = parse_ok(&edit(
        "<instance_camera url=\"#cam\"/>",
        "<instance_camera url=\"#gone\"/>",
    ));
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("#gone") && s.warnings[0].contains("default view"));
}

/// An emissive mesh flattened to nothing emits nothing: the render's "image will be
/// black" check must not count it.
#[test]
fn only_surfaces_with_area_emit() {
    let emissive = effect_doc(
        "<lambert><emission><color>2 3 4 1</color></emission><diffuse><color>0 0 0 1</color></diffuse></lambert>",
    );
    assert!(parse_ok(&emissive).has_emitting_surface());
    let flat = edit_doc(
        &emissive,
        "<matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix>",
        "<scale>0 0 0</scale>",
    );
    assert!(!parse_ok(&flat).has_emitting_surface());
    assert!(!parse_ok(TEMPLATE).has_emitting_surface());
}
