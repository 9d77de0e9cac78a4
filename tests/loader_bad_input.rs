//! Bad input gives a one-line `FILE: <element>: what` error (or, where the
//! spec has a safe default, a warning) and never a panic.

use crate::common;

use common::{edit, parse_err, parse_ok, TEMPLATE};
use ember::scene::collada::{load, parse};
use std::io::Write;

#[test]
fn template_is_valid_and_warning_free() {
    let s = parse_ok(TEMPLATE);
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.spheres.len(), 1);
    assert_eq!(s.lights.len(), 1);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

#[test]
fn truncated_xml() {
    for cut in [1, 100, TEMPLATE.len() / 2, TEMPLATE.len() - 12] {
        parse_err(&TEMPLATE[..cut], &["not well-formed XML"]);
    }
}

#[test]
fn malformed_xml() {
    parse_err(&edit("</mesh>", "</mush>"), &["not well-formed XML"]);
    parse_err(&edit("count=\"12\"", "count=12"), &["not well-formed XML"]);
}

#[test]
fn non_collada_xml() {
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg"><rect/></svg>"#;
    parse_err(svg, &["<svg>", "not a COLLADA file"]);
}

#[test]
fn empty_file() {
    parse_err("", &["file is empty"]);
    parse_err(" \n\t ", &["file is empty"]);
}

#[test]
fn binary_file() {
    parse_err("\0\u{1}\u{2}PK\u{3}\u{4}", &["not well-formed XML"]);
    let mut f = tempfile::NamedTempFile::new().unwrap();
    f.write_all(&[0x89, b'P', b'N', b'G', 0xff, 0xfe, 0x00, 0x9f])
        .unwrap();
    let msg = load(f.path()).unwrap_err().to_string();
    assert!(msg.starts_with(&f.path().display().to_string()), "{msg}");
    assert!(msg.contains("invalid UTF-8"), "{msg}");
}

#[test]
fn missing_file_names_the_path() {
    let msg = load(std::path::Path::new("/nonexistent/scene.dae"))
        .unwrap_err()
        .to_string();
    assert!(msg.starts_with("/nonexistent/scene.dae: "), "{msg}");
}

#[test]
fn float_array_with_fewer_numbers_than_count() {
    let doc = edit("0 0 0 1 0 0 1 1 0 0 1 0<", "0 0 0 1 0 0 1 1 0 0 1<");
    let msg = parse_err(&doc, &[]);
    assert_eq!(
        msg,
        "scene.dae: <float_array id=\"quad-pos-array\">: count is 12 but 11 numbers are present"
    );
}

#[test]
fn float_array_with_non_finite_numbers() {
    for bad in ["inf", "-inf", "NaN", "nan", "1e39", "abc", "0x10"] {
        let doc = edit(
            "0 0 0 1 0 0 1 1 0 0 1 0<",
            &format!("0 0 0 1 {bad} 0 1 1 0 0 1 0<"),
        );
        parse_err(
            &doc,
            &[
                "<float_array id=\"quad-pos-array\">",
                "entry 4",
                "not a finite number",
            ],
        );
    }
}

#[test]
fn absurd_count_is_not_preallocated() {
    let doc = edit("count=\"12\"", "count=\"18446744073709551615\"");
    parse_err(
        &doc,
        &[
            "<float_array id=\"quad-pos-array\">",
            "count is 18446744073709551615",
        ],
    );
    let doc = edit(
        "count=\"4\" stride=\"3\"",
        "count=\"4000000000\" stride=\"3\"",
    );
    parse_err(
        &doc,
        &[
            "<source id=\"quad-pos\">/technique_common/accessor",
            "count 4000000000",
            "the array has 12",
        ],
    );
    let doc = edit(
        "<polylist material=\"grey-sym\" count=\"2\"",
        "<polylist material=\"grey-sym\" count=\"3000000000\"",
    );
    parse_err(&doc, &["polylist", "count is 3000000000"]);
}

#[test]
fn position_index_out_of_range() {
    let doc = edit("<p>0 0 1 0 2 0", "<p>0 0 1 0 7 0");
    parse_err(
        &doc,
        &[
            "<geometry id=\"quad\">/mesh/polylist/p",
            "face 0",
            "position index 7 is out of range",
        ],
    );
}

#[test]
fn normal_index_out_of_range() {
    let doc = edit("<p>0 0 1 0 2 0 0 0 2 0 3 0", "<p>0 0 1 0 2 0 0 0 2 0 3 4");
    parse_err(
        &doc,
        &["polylist/p", "face 1", "normal index 4 is out of range"],
    );
}

#[test]
fn negative_vcount() {
    let doc = edit("<vcount>3 3</vcount>", "<vcount>-3 3</vcount>");
    parse_err(
        &doc,
        &["polylist/vcount", "\"-3\"", "not a non-negative integer"],
    );
}

#[test]
fn inconsistent_vcount() {
    let doc = edit("<vcount>3 3</vcount>", "<vcount>3 4</vcount>");
    parse_err(
        &doc,
        &["polylist/vcount", "7 corners", "<p> has 12 indices"],
    );
    let doc = edit("<vcount>3 3</vcount>", "<vcount>3 3 0</vcount>");
    parse_err(&doc, &["polylist", "count is 2 but 3 faces"]);
    // A face of no corners is skipped with a warning (loader_exporters.rs).
    let doc = edit("<vcount>3 3</vcount>", "<vcount>6 0</vcount>");
    let s = parse_ok(&doc);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("polylist: a face of fewer than 3 corners")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn negative_or_garbage_index() {
    let doc = edit("<p>0 0 1 0 2 0", "<p>0 0 -1 0 2 0");
    parse_err(&doc, &["polylist/p", "\"-1\""]);
    let doc = edit("<p>0 0 1 0 2 0", "<p>0 0 x 0 2 0");
    parse_err(&doc, &["polylist/p", "entry 2"]);
}

#[test]
fn matrix_with_more_than_16_entries() {
    let doc = edit(
        "0 0 1 0 0 0 0 1</matrix>\n        <instance_geometry",
        "0 0 1 0 0 0 0 1 0</matrix>\n        <instance_geometry",
    );
    parse_err(
        &doc,
        &["<node id=\"quad-node\">/matrix", "17 numbers, expected 16"],
    );
}

#[test]
fn matrix_with_no_entries() {
    let doc = edit(
        "<matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix>",
        "<matrix> </matrix>",
    );
    parse_err(&doc, &["<node id=\"quad-node\">/matrix", "no numbers"]);
}

#[test]
fn short_matrix_is_padded_with_a_warning() {
    // 12 numbers: the bottom row becomes 0 0 0 0, which makes points non-finite...
    let doc = edit(
        "<matrix>1 0 0 0 0 0 -1 -3 0 1 0 1 0 0 0 1</matrix>",
        "<matrix>1 0 0 0 0 0 -1 -3 0 1 0 1</matrix>",
    );
    // ...but the camera only uses its linear part, so this loads.
    let s = parse_ok(&doc);
    assert!(s
        .warnings
        .iter()
        .any(|w| w.contains("<node id=\"cam-node\">/matrix") && w.contains("12 numbers")));
}

#[test]
fn bad_translate_rotate_scale() {
    let doc = edit("<translate>0 0 1</translate>", "<translate>0 0</translate>");
    parse_err(
        &doc,
        &[
            "<node id=\"ball-node\">/translate",
            "expected 3 numbers, found 2",
        ],
    );
    let doc = edit("<translate>0 0 1</translate>", "<rotate>0 0 1</rotate>");
    parse_err(
        &doc,
        &[
            "<node id=\"ball-node\">/rotate",
            "expected 4 numbers, found 3",
        ],
    );
    let doc = edit("<translate>0 0 1</translate>", "<scale>1 1 1 1</scale>");
    parse_err(
        &doc,
        &[
            "<node id=\"ball-node\">/scale",
            "expected 3 numbers, found 4",
        ],
    );
}

#[test]
fn url_that_names_nothing() {
    let cases = [
        (
            "<instance_geometry url=\"#quad\">",
            "<instance_geometry url=\"#nothing\">",
            "<node id=\"quad-node\">/instance_geometry",
        ),
        (
            "<instance_effect url=\"#grey-fx\"/>",
            "<instance_effect url=\"#nothing\"/>",
            "<material id=\"grey\">/instance_effect",
        ),
        (
            "source=\"#quad-pos\"",
            "source=\"#nothing\"",
            "<vertices id=\"quad-vtx\">/input",
        ),
        (
            "source=\"#quad-nrm\"",
            "source=\"#nothing\"",
            "polylist/input[1]",
        ),
        (
            "source=\"#quad-vtx\"",
            "source=\"#nothing\"",
            "polylist/input[0]",
        ),
        (
            "<instance_visual_scene url=\"#main\"/>",
            "<instance_visual_scene url=\"#nothing\"/>",
            "instance_visual_scene",
        ),
    ];
    for (from, to, element) in cases {
        parse_err(&edit(from, to), &[element, "\"#nothing\" names nothing"]);
    }
}

#[test]
fn url_naming_the_wrong_kind_of_element() {
    let doc = edit(
        "<instance_geometry url=\"#quad\">",
        "<instance_geometry url=\"#grey\">",
    );
    parse_err(&doc, &["names a <material>, expected a <geometry>"]);
    let doc = edit(
        "<instance_geometry url=\"#quad\">",
        "<instance_geometry url=\"quad.dae#quad\">",
    );
    parse_err(&doc, &["not a local #id reference"]);
}

/// `n` nested `<node>`s, the innermost holding the quad.
fn nested(n: usize) -> String {
    let inner = "<instance_geometry url=\"#quad\"/>";
    let nodes = format!("{}{inner}{}", "<node>".repeat(n), "</node>".repeat(n));
    edit(
        "<node id=\"ball-node\">",
        &format!("{nodes}<node id=\"ball-node\">"),
    )
}

#[test]
fn deep_nesting_within_the_cap_loads() {
    let s = parse_ok(&nested(200));
    assert_eq!(s.triangles.len(), 4);
}

#[test]
fn very_deep_nesting_is_an_error_not_a_stack_overflow() {
    let msg = parse_err(
        &nested(300),
        &[
            "<visual_scene id=\"main\">/…/node/node",
            "deeper than 256 levels",
        ],
    );
    assert!(msg.len() < 200, "the element path is abbreviated: {msg}");
    // Just within the XML depth cap: roxmltree (which recurses per element)
    // must survive it on a test thread's stack, then the node cap applies.
    parse_err(&nested(1000), &["deeper than 256 levels"]);
    // Far deeper than any call stack would survive: refused before XML parsing.
    parse_err(
        &nested(200_000),
        &["line 56, column", "nested deeper than 1024 levels"],
    );
}

#[test]
fn non_finite_transformed_position() {
    let doc = edit(
        "<matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix>",
        "<matrix>1e300 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix>",
    );
    parse_err(
        &doc,
        &["<node id=\"quad-node\">/instance_geometry", "not finite"],
    );
}

#[test]
fn bad_sphere_radius() {
    for (r, what) in [
        ("-1", "not positive"),
        ("0", "not positive"),
        ("inf", "not a finite number"),
        ("", "expected at least 1"),
    ] {
        let doc = edit("<radius>0.5</radius>", &format!("<radius>{r}</radius>"));
        parse_err(&doc, &["<geometry id=\"ball\">", "sphere", what]);
    }
}

#[test]
fn light_without_colour() {
    let doc = edit("<point><color>1 2 3</color></point>", "<point/>");
    parse_err(
        &doc,
        &[
            "<light id=\"lamp\">/technique_common/point",
            "missing <color>",
        ],
    );
}

#[test]
fn bad_field_of_view() {
    let doc = edit("<xfov>40</xfov>", "<xfov>180</xfov>");
    parse_err(
        &doc,
        &["<camera id=\"cam\">", "xfov", "not a field of view"],
    );
    let doc = edit(
        "<aspect_ratio>1.5</aspect_ratio>",
        "<aspect_ratio>-1</aspect_ratio>",
    );
    parse_err(&doc, &["aspect_ratio", "not positive"]);
}

#[test]
fn missing_camera_is_a_warning() {
    let doc = edit("<instance_camera url=\"#cam\"/>", "");
    let s = parse_ok(&doc);
    assert!(
        s.warnings.iter().any(|w| w.contains("no camera")),
        "{:?}",
        s.warnings
    );
    assert_eq!(s.camera, ember::scene::CameraDesc::default());
}

#[test]
fn missing_material_is_a_warning() {
    let doc = edit(
        "<instance_material symbol=\"grey-sym\" target=\"#grey\"/>",
        "",
    );
    let s = parse_ok(&doc);
    assert!(s
        .warnings
        .iter()
        .any(|w| w.contains("<node id=\"quad-node\">/instance_geometry")
            && w.contains("default Lambertian")));
    assert_eq!(
        s.materials[s.triangles[0].material as usize],
        ember::materials::Material::default()
    );
}

#[test]
fn unknown_light_type_is_a_warning() {
    let doc = edit(
        "<point><color>1 2 3</color></point>",
        "<photometric><color>1 2 3</color></photometric>",
    );
    let s = parse_ok(&doc);
    assert!(s.lights.is_empty());
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("photometric lights are not supported")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn scene_without_geometry_is_empty_not_an_error() {
    let s = parse_ok(r#"<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema"/>"#);
    assert!(s.triangles.is_empty() && s.spheres.is_empty() && s.lights.is_empty());
    assert!(s.bounds.is_empty());
    // The template with every geometry node and geometry removed: camera and light only.
    let cut = |doc: &str, from: &str, to: &str| {
        let start = doc.find(from).unwrap();
        let end = doc.find(to).unwrap();
        format!("{}{}", &doc[..start], &doc[end..])
    };
    let no_nodes = cut(
        TEMPLATE,
        "<node id=\"quad-node\">",
        "<node id=\"lamp-node\">",
    );
    let doc = cut(&no_nodes, "<geometry id=\"quad\">", "</library_geometries>");
    let s = parse_ok(&doc);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.lights.len(), 1);
    assert!(s.triangles.is_empty());
    // With its geometry left in the library but instanced nowhere, the mesh is placed
    // once, untransformed, with a warning (as assimp and other importers do).
    let s = parse_ok(&no_nodes);
    assert_eq!(s.triangles.len(), 2);
    assert!(s.spheres.is_empty(), "only meshes are placed");
    assert!(s
        .warnings
        .iter()
        .any(|w| w.contains("instances no geometry")));
}

#[test]
fn parse_and_load_agree() {
    let mut f = tempfile::NamedTempFile::new().unwrap();
    f.write_all(TEMPLATE.as_bytes()).unwrap();
    let a = load(f.path()).unwrap();
    let b = parse(TEMPLATE, "x").unwrap();
    assert_eq!(a.triangles, b.triangles);
    assert_eq!(a.positions, b.positions);
}
