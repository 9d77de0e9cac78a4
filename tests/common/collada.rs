//! A small valid COLLADA document that the loader tests mutate.

use ember::scene::collada::parse;
use ember::scene::Scene;
use ember::Vec3;

/// A unit quad (two triangles with normals), a sphere, a point light and a
/// camera, Z_UP like the course files. Loads without warnings.
pub const TEMPLATE: &str = r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><up_axis>Z_UP</up_axis></asset>
  <library_lights>
    <light id="lamp"><technique_common><point><color>1 2 3</color></point></technique_common></light>
  </library_lights>
  <library_cameras>
    <camera id="cam"><optics><technique_common><perspective>
      <xfov>40</xfov><aspect_ratio>1.5</aspect_ratio>
    </perspective></technique_common></optics></camera>
  </library_cameras>
  <library_effects>
    <effect id="grey-fx"><profile_COMMON><technique sid="common"><lambert>
      <diffuse><color>0.3 0.3 0.3 1</color></diffuse>
    </lambert></technique></profile_COMMON></effect>
    <effect id="chrome-fx"><extra><technique profile="CGL">
      <mirror><reflectance>0.9 0.9 0.9</reflectance></mirror>
    </technique></extra></effect>
  </library_effects>
  <library_materials>
    <material id="grey"><instance_effect url="#grey-fx"/></material>
    <material id="chrome"><instance_effect url="#chrome-fx"/></material>
  </library_materials>
  <library_geometries>
    <geometry id="quad">
      <mesh>
        <source id="quad-pos">
          <float_array id="quad-pos-array" count="12">0 0 0 1 0 0 1 1 0 0 1 0</float_array>
          <technique_common><accessor source="#quad-pos-array" count="4" stride="3"/></technique_common>
        </source>
        <source id="quad-nrm">
          <float_array id="quad-nrm-array" count="3">0 0 1</float_array>
          <technique_common><accessor source="#quad-nrm-array" count="1" stride="3"/></technique_common>
        </source>
        <vertices id="quad-vtx"><input semantic="POSITION" source="#quad-pos"/></vertices>
        <polylist material="grey-sym" count="2">
          <input semantic="VERTEX" source="#quad-vtx" offset="0"/>
          <input semantic="NORMAL" source="#quad-nrm" offset="1"/>
          <vcount>3 3</vcount>
          <p>0 0 1 0 2 0 0 0 2 0 3 0</p>
        </polylist>
      </mesh>
    </geometry>
    <geometry id="ball"><extra><technique profile="CGL">
      <sphere><radius>0.5</radius></sphere>
    </technique></extra></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="main">
      <node id="quad-node">
        <matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix>
        <instance_geometry url="#quad"><bind_material><technique_common>
          <instance_material symbol="grey-sym" target="#grey"/>
        </technique_common></bind_material></instance_geometry>
      </node>
      <node id="ball-node">
        <translate>0 0 1</translate>
        <instance_geometry url="#ball"><bind_material><technique_common>
          <instance_material symbol="chrome" target="#chrome"/>
        </technique_common></bind_material></instance_geometry>
      </node>
      <node id="lamp-node"><translate>0 0 3</translate><instance_light url="#lamp"/></node>
      <node id="cam-node">
        <matrix>1 0 0 0 0 0 -1 -3 0 1 0 1 0 0 0 1</matrix>
        <instance_camera url="#cam"/>
      </node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#main"/></scene>
</COLLADA>
"##;

/// The template with `from` replaced by `to`; `from` must occur exactly once.
pub fn edit(from: &str, to: &str) -> String {
    edit_doc(TEMPLATE, from, to)
}

pub fn edit_doc(doc: &str, from: &str, to: &str) -> String {
    assert_eq!(doc.matches(from).count(), 1, "{from:?} must occur once");
    doc.replacen(from, to, 1)
}

pub fn parse_ok(doc: &str) -> Scene {
    parse(doc, "scene.dae").unwrap_or_else(|e| panic!("{e}"))
}

/// Parses `doc`, expecting a one-line error naming the file and containing every needle.
pub fn parse_err(doc: &str, needles: &[&str]) -> String {
    let msg = match parse(doc, "scene.dae") {
        Ok(s) => panic!(
            "expected an error, got a scene with warnings {:?}",
            s.warnings
        ),
        Err(e) => e.to_string(),
    };
    assert!(msg.starts_with("scene.dae: "), "{msg}");
    assert!(!msg.contains('\n'), "not one line: {msg}");
    for n in needles {
        assert!(msg.contains(n), "{msg:?} does not contain {n:?}");
    }
    msg
}

/// The template's libraries with `up_axis` replaced, `libs` (whole
/// `<library_*>` elements) added, and the visual scene's content replaced by `nodes`.
pub fn scene_doc(up: &str, libs: &str, nodes: &str) -> String {
    let doc = edit(
        "<up_axis>Z_UP</up_axis>",
        &format!("<up_axis>{up}</up_axis>"),
    );
    let doc = edit_doc(
        &doc,
        "<library_visual_scenes>",
        &format!("{libs}\n<library_visual_scenes>"),
    );
    let start =
        doc.find("<visual_scene id=\"main\">").unwrap() + "<visual_scene id=\"main\">".len();
    let end = doc.find("</visual_scene>").unwrap();
    format!("{}{nodes}{}", &doc[..start], &doc[end..])
}

/// `<instance_geometry>` of `url` binding `symbol` to `#target`.
pub fn geometry_instance(url: &str, symbol: &str, target: &str) -> String {
    format!(
        r##"<instance_geometry url="#{url}"><bind_material><technique_common>
             <instance_material symbol="{symbol}" target="#{target}"/>
           </technique_common></bind_material></instance_geometry>"##
    )
}

/// The template's quad, bound to its grey material.
pub fn quad_instance() -> String {
    geometry_instance("quad", "grey-sym", "grey")
}

/// Whether two points agree to within the loader's f32 rounding.
pub fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

pub fn assert_close(a: Vec3, b: Vec3) {
    assert!(close(a, b), "{a} is not {b}");
}

/// How many of the scene's warnings contain `needle`.
pub fn count_warnings(s: &Scene, needle: &str) -> usize {
    s.warnings.iter().filter(|w| w.contains(needle)).count()
}
