//! Skinned meshes (`<instance_controller>` of a `<skin>`): placed by COLLADA's
//! linear-blend skinning equation at the joints' pose in the visual scene, whatever
//! the exporter's convention for its bind matrices; bad skinning data is a one-line
//! error naming the element.

use crate::common;

use common::{assert_close, count_warnings, parse_err, parse_ok, quad_instance, scene_doc};
use ember::scene::collada::load;
use ember::scene::Scene;
use ember::Vec3;
use std::path::Path;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/collada");

/// A skin of the template's quad without `<joints>` or `<vertex_weights>`, instanced
/// directly and through a morph, under a node moved by 100.
fn skin_doc(bind_shape: &str) -> String {
    let libs = format!(
        r##"<library_controllers><controller id="skin"><skin source="#quad">
             <bind_shape_matrix>{bind_shape}</bind_shape_matrix>
             <source id="joints"><Name_array id="joints-a" count="1">bone</Name_array></source>
           </skin></controller>
           <controller id="morph"><morph source="#skin" method="NORMALIZED"/></controller></library_controllers>"##
    );
    let nodes = r##"<node><translate>100 0 0</translate>
        <instance_controller url="#morph"><skeleton>#bone</skeleton><bind_material><technique_common>
          <instance_material symbol="grey-sym" target="#grey"/></technique_common></bind_material></instance_controller></node>
        <node><instance_controller url="#skin"/></node>"##;
    scene_doc("Y_UP", &libs, nodes)
}

#[test]
fn skins_without_joint_weights_load_at_their_bind_pose_with_one_warning() {
    let s = parse_ok(&skin_doc("1 0 0 0  0 1 0 2  0 0 1 0  0 0 0 1"));
    assert_eq!(s.triangles.len(), 4);
    // bind_shape_matrix moves the quad up by 2; the instancing node's translation
    // does not enter (at the bind pose the skin is in world space).
    assert_close(s.positions[1], Vec3::new(1.0, 2.0, 0.0));
    assert_eq!(count_warnings(&s, "bind pose"), 1, "{:?}", s.warnings);
    parse_err(
        &skin_doc("1 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1")
            .replace("source=\"#quad\"", "source=\"#nothing\""),
        &["<controller id=\"skin\">/skin", "names no geometry"],
    );
    // A short bind shape matrix would send every vertex to infinity: refused, naming it.
    parse_err(
        &skin_doc("1 0 0"),
        &[
            "<controller id=\"skin\">/skin/bind_shape_matrix",
            "has 3 numbers",
            "needs 16",
        ],
    );
}

#[test]
fn an_assimp_skin_lands_where_its_plain_mesh_does() {
    // Assimp's inverse bind matrix is relative to the mesh node: the bone's world
    // matrix times it is the Cube node's translation by 3, which the bind shape alone lost.
    let skinned = load(&Path::new(DATA).join("assimp_skin.dae")).unwrap();
    let plain = load(&Path::new(DATA).join("assimp_skin_reference.dae")).unwrap();
    assert_eq!(skinned.positions.len(), plain.positions.len());
    for (a, b) in skinned.positions.iter().zip(&plain.positions) {
        assert_close(*a, *b);
    }
    assert_close(skinned.bounds.min, plain.bounds.min);
    assert_close(skinned.bounds.max, plain.bounds.max);
    let corner = |s: &Scene, t: usize, k: usize| {
        let tri = &s.triangles[t];
        (
            s.positions[tri.v[k] as usize],
            s.normals[tri.n.unwrap()[k] as usize],
        )
    };
    for t in 0..plain.triangles.len() {
        for k in 0..3 {
            let ((p, n), (q, m)) = (corner(&skinned, t, k), corner(&plain, t, k));
            assert_close(p, q);
            assert_close(n, m);
        }
    }
    assert_eq!(
        count_warnings(&skinned, "joint pose"),
        1,
        "{:?}",
        skinned.warnings
    );
}

/// Blender's convention: the armature at rest, each joint's world matrix the inverse
/// of its inverse bind matrix (here a turn of 90° about z after a move by 3 in x), a
/// bind shape moving the mesh up by 2 and a Z_UP file. Joints are named by sid, and
/// without a `<skeleton>` are looked for in the whole visual scene.
fn blender_rest_doc() -> String {
    let libs = r##"<library_controllers><controller id="Armature_Quad-skin"><skin source="#quad">
        <bind_shape_matrix>1 0 0 0  0 1 0 0  0 0 1 2  0 0 0 1</bind_shape_matrix>
        <source id="rest-joints"><Name_array id="rest-joints-a" count="1">Bone</Name_array></source>
        <source id="rest-ibm"><float_array id="rest-ibm-a" count="16">0 1 0 0  -1 0 0 3  0 0 1 0  0 0 0 1</float_array>
          <technique_common><accessor source="#rest-ibm-a" count="1" stride="16"/></technique_common></source>
        <source id="rest-w"><float_array id="rest-w-a" count="1">1</float_array></source>
        <joints><input semantic="JOINT" source="#rest-joints"/><input semantic="INV_BIND_MATRIX" source="#rest-ibm"/></joints>
        <vertex_weights count="4"><input semantic="JOINT" source="#rest-joints" offset="0"/>
          <input semantic="WEIGHT" source="#rest-w" offset="1"/>
          <vcount>1 1 1 1</vcount><v>0 0  0 0  0 0  0 0</v></vertex_weights>
      </skin></controller></library_controllers>"##;
    let nodes = r##"<node id="Armature"><translate>3 0 0</translate>
          <node id="Armature_Bone" name="Bone" sid="Bone" type="JOINT"><rotate>0 0 1 90</rotate></node>
        </node>
        <node id="Quad"><translate>0 0 50</translate>
          <instance_controller url="#Armature_Quad-skin"><bind_material><technique_common>
            <instance_material symbol="grey-sym" target="#grey"/></technique_common></bind_material>
          </instance_controller></node>"##;
    scene_doc("Z_UP", libs, nodes)
}

#[test]
fn a_skin_at_rest_stays_at_its_bind_shape() {
    let s = parse_ok(&blender_rest_doc());
    // The template's quad moved up by 2 (z in the file), then Z_UP's (x, y, z) → (−x, z, y).
    let quad = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    for (p, (x, y)) in s.positions.iter().zip(quad) {
        assert_close(*p, Vec3::new(-x, 2.0, y));
    }
    assert_close(s.normals[0], Vec3::Y);
}

/// The template's quad (corners (0,0,0), (1,0,0), (1,1,0), (0,1,0), normal +z) skinned
/// to `hip`, turned 90° about y under a parent moved by 5 in y, and `tip`, moved by 2
/// in z. Vertex 0 follows the tip, vertex 1 the hip, vertex 2 both half and half, and
/// vertex 3 the bind shape (joint −1) with a weight of 2, normalised. The instancing
/// node's move by 100 does not enter; a plain instance of the quad follows.
fn posed_doc() -> String {
    let libs = r##"<library_controllers><controller id="rig"><skin source="#quad">
        <bind_shape_matrix>1 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1</bind_shape_matrix>
        <source id="rig-joints"><Name_array id="rig-joints-a" count="2">hip tip</Name_array></source>
        <source id="rig-ibm"><float_array id="rig-ibm-a" count="32">
          1 0 0 0  0 1 0 -5  0 0 1 0  0 0 0 1
          1 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1</float_array>
          <technique_common><accessor source="#rig-ibm-a" count="2" stride="16"/></technique_common></source>
        <source id="rig-w"><float_array id="rig-w-a" count="3">1 0.5 2</float_array>
          <technique_common><accessor source="#rig-w-a" count="3" stride="1"/></technique_common></source>
        <joints><input semantic="JOINT" source="#rig-joints"/><input semantic="INV_BIND_MATRIX" source="#rig-ibm"/></joints>
        <vertex_weights count="4"><input semantic="JOINT" source="#rig-joints" offset="0"/>
          <input semantic="WEIGHT" source="#rig-w" offset="1"/>
          <vcount>1 1 2 1</vcount><v>1 0  0 0  0 1 1 1  -1 2</v></vertex_weights>
      </skin></controller></library_controllers>"##;
    let nodes = format!(
        r##"<node id="arm"><translate>0 5 0</translate>
          <node id="decoy" name="hip"><translate>50 0 0</translate></node>
          <node id="arm-hip" sid="hip" name="Hip"><rotate>0 1 0 90</rotate></node>
        </node>
        <node id="arm-tip" sid="tip"><translate>0 0 2</translate></node>
        <node><translate>100 0 0</translate>
          <instance_controller url="#rig"><skeleton>#arm</skeleton><skeleton>#arm-tip</skeleton>
            <bind_material><technique_common><instance_material symbol="grey-sym" target="#grey"/>
            </technique_common></bind_material></instance_controller></node>
        <node><translate>0 0 -10</translate>{}</node>"##,
        quad_instance()
    );
    scene_doc("Y_UP", libs, &nodes)
}

#[test]
fn a_posed_skin_follows_its_joints() {
    let s = parse_ok(&posed_doc());
    let tip = Vec3::new(0.0, 0.0, 2.0);
    // (1, 0, 0) turned 90° about y; (1, 1, 0) half that way ((0, 1, −1)), half moved by 2 in z.
    let hip = Vec3::new(0.0, 0.0, -1.0);
    let half = (Vec3::new(0.0, 1.0, -1.0) + Vec3::new(1.0, 1.0, 2.0)) / 2.0;
    for (p, q) in s.positions[..4].iter().zip([tip, hip, half, Vec3::Y]) {
        assert_close(*p, q);
    }
    // The normal at vertex 1 turns with the hip: +z about y is +x.
    let at_hip = s.triangles[..2]
        .iter()
        .flat_map(|t| t.v.iter().zip(t.n.unwrap()))
        .find(|(v, _)| **v == 1)
        .map(|(_, n)| s.normals[n as usize])
        .unwrap();
    assert_close(at_hip, Vec3::X);
    // The plain instance of the same geometry is not posed by the skin before it.
    assert_close(s.positions[6], Vec3::new(1.0, 1.0, -10.0));
    assert_eq!(count_warnings(&s, "normalised"), 1, "{:?}", s.warnings);
}

#[test]
fn bad_skinning_data_is_an_error_naming_the_element() {
    let doc = posed_doc();
    parse_err(
        &doc.replace("hip tip<", "hip nobody<"),
        &[
            "<Name_array id=\"rig-joints-a\">",
            "joint \"nobody\" matches no node",
        ],
    );
    parse_err(
        &doc.replace("0 1 1 1  -1 2", "0 1 1 7  -1 2"),
        &[
            "<controller id=\"rig\">/skin/vertex_weights/v",
            "vertex 2: weight index 7 is out of range",
        ],
    );
    parse_err(
        &doc.replace("0 1 1 1  -1 2", "0 1 2 1  -1 2"),
        &[
            "vertex_weights/v",
            "vertex 2: joint index 2 is out of range",
        ],
    );
    parse_err(
        &doc.replace("<vcount>1 1 2 1", "<vcount>1 1 2 2"),
        &["vertex_weights/v", "has 10 indices, but <vcount> needs 12"],
    );
    parse_err(
        &doc.replace("<vcount>1 1 2 1", "<vcount>1 1 2"),
        &["vertex_weights/vcount", "has 3 entries for 4 vertices"],
    );
    parse_err(
        &doc.replace("vertex_weights count=\"4\"", "vertex_weights count=\"3\""),
        &[
            "vertex_weights",
            "count 3, but the skinned mesh has 4 vertices",
        ],
    );
    parse_err(
        &doc.replace("count=\"2\" stride=\"16\"", "count=\"1\" stride=\"16\""),
        &[
            "<source id=\"rig-ibm\">",
            "1 inverse bind matrices for 2 joints",
        ],
    );
    parse_err(
        &doc.replace("0 1 0 -5", "0 1 0 NaN"),
        &[
            "<float_array id=\"rig-ibm-a\">",
            "\"NaN\" is not a finite number",
        ],
    );
}
