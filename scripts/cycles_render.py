#!/usr/bin/env python3
"""Renders a scene exported by `ember export --format mitsuba` with Blender Cycles
(bpy 4.5, see scripts/cycles-env) and prints one JSON line per timed render.

The Mitsuba export is the one place that states what ember renders (camera,
materials, lights, path length); this script only translates it into bpy, and
refuses (exit 2, naming the element) whatever it cannot translate exactly:
  - ply shapes and spheres (spheres as Cycles points, which it intersects as
    true spheres) with a twosided diffuse BSDF or a black diffuse one;
  - area emitters on a rectangle of two triangles, as a Blender area light of
    shape RECTANGLE, power L*pi*area with `normalize` on, facing along its local
    -Z, seen by camera rays; the rectangle's own black surface stays, moved a
    hair behind the light, so it blocks light arriving from behind as ember's does;
  - other emitting surfaces as meshes with an emission shader of radiance L on
    their front side (black behind), sampled as lights from the front;
  - the path integrator's max_depth (m + 1) as Cycles' max_bounces = m - 1
    (Cycles counts bounces after the first hit); roulette starts at the same
    vertex (min_light_bounces = rr_depth - 1), Cycles' own survival probability;
  - a box pixel filter one pixel wide; no adaptive sampling, denoising, clamping
    or glossy blur; black world; linear Rec.709 output (Blender's working space).

Cycles' render call has a fixed cost (scene sync, kernel set-up). Each timed
render is preceded by a 1-spp render of the same scene, and `seconds` is
(t(N) - t(1)) * N / (N - 1): the time N samples take without that cost.

With --reference REF.exr the image is compared with the reference: its mean per
channel against the reference manifest's mean_rgb (manifest.json beside REF),
within 1 % plus 4 standard errors of the render's mean, and its RMSE; the result
is printed ("mean check: ...") and the exit status is 3 when the means disagree.
"""
import argparse
import json
import math
import os
import sys
import time
import xml.etree.ElementTree as ET


def fail(msg, code=2):
    print(f"cycles_render: {msg}", file=sys.stderr)
    sys.exit(code)


def floats(text):
    return [float(x) for x in text.replace(",", " ").split()]


def child(elem, tag, name):
    for c in elem.findall(tag):
        if c.get("name") == name:
            return c
    return None


def value(elem, tag, name, default=None):
    c = child(elem, tag, name)
    return default if c is None else c.get("value")


def point(elem, name):
    c = child(elem, "point", name)
    return [float(c.get(k)) for k in "xyz"]


def read_ply(path):
    """Vertices (positions, normals or None) and triangles of a binary PLY as ember writes it."""
    import numpy as np
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline()
            if not line:
                fail(f"{path}: truncated PLY header")
            line = line.decode("ascii").strip()
            header.append(line)
            if line == "end_header":
                break
        data = f.read()
    if "format binary_little_endian 1.0" not in header:
        fail(f"{path}: only binary little-endian PLY is read")
    elements, current = [], None
    for line in header:
        parts = line.split()
        if parts[0] == "element":
            current = [parts[1], int(parts[2]), []]
            elements.append(current)
        elif parts[0] == "property":
            current[2].append(parts[1:])
    types = {"float": "<f4", "double": "<f8", "int": "<i4", "uint": "<u4", "uchar": "u1"}
    vertices = faces = None
    offset = 0
    for name, count, props in elements:
        if name == "vertex":
            dtype = np.dtype([(p[1], types[p[0]]) for p in props])
            vertices = np.frombuffer(data, dtype, count, offset)
        elif name == "face":
            if props != [["list", "uchar", "int", "vertex_indices"]]:
                fail(f"{path}: unexpected face properties {props}")
            dtype = np.dtype([("n", "u1"), ("i", "<i4", 3)])
            faces = np.frombuffer(data, dtype, count, offset)
            if count and (faces["n"] != 3).any():
                fail(f"{path}: only triangles are read")
        else:
            fail(f"{path}: unexpected element {name}")
        offset += dtype.itemsize * count
    pos = np.stack([vertices[k] for k in "xyz"], axis=1).astype(np.float64)
    nrm = None
    if "nx" in vertices.dtype.names:
        nrm = np.stack([vertices[k] for k in ("nx", "ny", "nz")], axis=1).astype(np.float64)
    return pos, nrm, faces["i"].astype(np.int64)


def bsdf_of(shape, where):
    """(kind, rgb) of a shape's BSDF: ('diffuse', albedo); anything else is refused."""
    b = shape.find("bsdf")
    if b is None:
        fail(f"{where}: shape without a bsdf")
    if b.get("type") == "twosided":
        b = b.find("bsdf")
    if b.get("type") != "diffuse":
        fail(f"{where}: bsdf '{b.get('type')}' has no exact Cycles counterpart here "
             "(only Lambertian surfaces, emission and area lights are translated)")
    return floats(value(b, "rgb", "reflectance", "0.5 0.5 0.5"))


def diffuse_material(bpy, rgb, cache):
    key = tuple(rgb)
    if key not in cache:
        m = bpy.data.materials.new(f"diffuse{len(cache)}")
        m.use_nodes = True
        nodes = m.node_tree.nodes
        nodes.clear()
        d = nodes.new("ShaderNodeBsdfDiffuse")
        d.inputs["Color"].default_value = (*rgb, 1.0)
        d.inputs["Roughness"].default_value = 0.0
        out = nodes.new("ShaderNodeOutputMaterial")
        m.node_tree.links.new(d.outputs["BSDF"], out.inputs["Surface"])
        cache[key] = m
    return cache[key]


def add_mesh(bpy, np, name, pos, nrm, tri, material):
    """A mesh of unshared triangles; per-corner normals become custom split normals,
    each turned to its triangle's side (Cycles shades a flat wall black otherwise)."""
    me = bpy.data.meshes.new(name)
    nv, nf = len(pos), len(tri)
    me.vertices.add(nv)
    me.vertices.foreach_set("co", pos.astype(np.float32).ravel())
    me.loops.add(3 * nf)
    me.loops.foreach_set("vertex_index", tri.astype(np.int32).ravel())
    me.polygons.add(nf)
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * nf, 3, dtype=np.int32))
    me.update(calc_edges=True)
    if nrm is not None:
        me.polygons.foreach_set("use_smooth", np.ones(nf, dtype=bool))
        p = pos[tri]
        face_n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        corner = nrm[tri]
        flip = np.einsum("fcj,fj->fc", corner, face_n) < 0
        corner[flip] *= -1
        me.normals_split_custom_set(corner.reshape(-1, 3).tolist())
    me.materials.append(material)
    obj = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def rectangle(np, pos, tri):
    """(corner, ex, ey, unit normal) of two triangles forming a rectangle wound toward
    its normal, else None."""
    if len(tri) != 2:
        return None
    p = pos[tri[0]]
    normal = np.cross(p[1] - p[0], p[2] - p[0])
    normal /= np.linalg.norm(normal)
    corners = np.unique(np.round(pos[tri].reshape(-1, 3), 9), axis=0)
    if len(corners) != 4:
        return None
    c0 = corners[0]
    far = np.argmax(np.linalg.norm(corners - c0, axis=1))
    a, b = [corners[i] for i in range(1, 4) if i != far]
    ex, ey = a - c0, b - c0
    size_x, size_y = np.linalg.norm(ex), np.linalg.norm(ey)
    if abs(np.dot(ex, ey)) > 1e-5 * size_x * size_y or \
            np.linalg.norm(c0 + ex + ey - corners[far]) > 1e-5 * (size_x + size_y):
        return None
    return c0, ex, ey, normal


def emission_material(bpy, radiance, name):
    """Emission of radiance L from the front side only (Cycles' emission shader of
    strength 1 emits radiance equal to its colour), black behind; Cycles samples
    only the front as a light."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    m.cycles.emission_sampling = "FRONT"
    nodes, links = m.node_tree.nodes, m.node_tree.links
    nodes.clear()
    emit = nodes.new("ShaderNodeEmission")
    emit.inputs["Color"].default_value = (*radiance, 1.0)
    emit.inputs["Strength"].default_value = 1.0
    black = nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    geometry = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(emit.outputs["Emission"], mix.inputs[1])
    links.new(black.outputs["BSDF"], mix.inputs[2])
    out = nodes.new("ShaderNodeOutputMaterial")
    links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return m


def area_light(bpy, np, name, pos, tri, radiance):
    """The Blender area light of a rectangle of two triangles wound toward its
    emitting side; returns the offset that moves its black surface behind it."""
    c0, ex, ey, normal = rectangle(np, pos, tri)
    size_x, size_y = np.linalg.norm(ex), np.linalg.norm(ey)
    x = ex / size_x
    z = -normal
    y = np.cross(z, x)
    centre = c0 + 0.5 * (ex + ey)
    scale = max(radiance)
    light = bpy.data.lights.new(name, "AREA")
    light.shape = "RECTANGLE"
    light.size, light.size_y = float(size_x), float(size_y)
    light.normalize = True
    light.color = [c / scale for c in radiance]
    light.energy = scale * math.pi * size_x * size_y
    obj = bpy.data.objects.new(name, light)
    import mathutils
    m = mathutils.Matrix(np.column_stack([x, y, z]).tolist()).to_4x4()
    m.translation = mathutils.Vector(centre.tolist())
    obj.matrix_world = m
    obj.visible_camera = True
    bpy.context.scene.collection.objects.link(obj)
    # ember's light surface is black and blocks what arrives from behind: keep it,
    # a hair behind the light so the camera and the light's own rays see the light.
    return normal * (-1e-5 * (size_x + size_y))


def add_sphere(bpy, name, centre, radius, material):
    """One Cycles point of `radius`: Cycles intersects points as exact spheres."""
    me = bpy.data.meshes.new(name)
    me.vertices.add(1)
    me.vertices[0].co = (0.0, 0.0, 0.0)
    obj = bpy.data.objects.new(name, me)
    obj.location = centre
    bpy.context.scene.collection.objects.link(obj)
    ng = bpy.data.node_groups.new(name, "GeometryNodeTree")
    ng.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    ng.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    n_in = ng.nodes.new("NodeGroupInput")
    n_out = ng.nodes.new("NodeGroupOutput")
    to_points = ng.nodes.new("GeometryNodeMeshToPoints")
    to_points.inputs["Radius"].default_value = radius
    set_mat = ng.nodes.new("GeometryNodeSetMaterial")
    set_mat.inputs["Material"].default_value = material
    ng.links.new(n_in.outputs[0], to_points.inputs["Mesh"])
    ng.links.new(to_points.outputs["Points"], set_mat.inputs["Geometry"])
    ng.links.new(set_mat.outputs["Geometry"], n_out.inputs[0])
    obj.modifiers.new(name, "NODES").node_group = ng


def camera(bpy, np, sensor, width, height):
    import mathutils
    if value(sensor, "string", "fov_axis", "x") != "x":
        fail("sensor: only fov_axis x is translated")
    la = sensor.find("transform").find("lookat")
    eye, target, up = (np.array(floats(la.get(k))) for k in ("origin", "target", "up"))
    f = target - eye
    f /= np.linalg.norm(f)
    right = np.cross(f, up)
    right /= np.linalg.norm(right)
    cam_up = np.cross(right, f)
    cam = bpy.data.cameras.new("camera")
    cam.sensor_fit = "HORIZONTAL"
    cam.angle = math.radians(float(value(sensor, "float", "fov")))
    cam.clip_start = float(value(sensor, "float", "near_clip", "1e-4"))
    cam.clip_end = float(value(sensor, "float", "far_clip", "1e4"))
    obj = bpy.data.objects.new("camera", cam)
    m = mathutils.Matrix(np.column_stack([right, cam_up, -f]).tolist()).to_4x4()
    m.translation = mathutils.Vector(eye.tolist())
    obj.matrix_world = m
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.scene.camera = obj


def build(bpy, np, xml_path, mesh_lights=False):
    """Builds the Cycles scene; returns (width, height, spp, max_depth)."""
    root = ET.parse(xml_path).getroot()
    folder = os.path.dirname(os.path.abspath(xml_path))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world
    integ = root.find("integrator")
    if integ is None or integ.get("type") != "path":
        fail(f"{xml_path}: only the path integrator is translated")
    max_depth = int(value(integ, "integer", "max_depth"))
    rr_depth = int(value(integ, "integer", "rr_depth", "5"))
    if max_depth < 1:
        fail(f"{xml_path}: max_depth {max_depth} (ember -m 0) has no Cycles counterpart")
    sensor = root.find("sensor")
    film = sensor.find("film")
    width = int(value(film, "integer", "width"))
    height = int(value(film, "integer", "height"))
    spp = int(value(sensor.find("sampler"), "integer", "sample_count"))
    camera(bpy, np, sensor, width, height)
    materials = {}
    for i, shape in enumerate(root.findall("shape")):
        where = f"{xml_path}: <shape> {i + 1} ({shape.get('type')})"
        emitter = shape.find("emitter")
        albedo = bsdf_of(shape, where)
        mat = diffuse_material(bpy, albedo, materials)
        if shape.get("type") == "sphere":
            if emitter is not None:
                fail(f"{where}: emissive spheres are not translated")
            add_sphere(bpy, f"sphere{i}", point(shape, "center"),
                       float(value(shape, "float", "radius")), mat)
            continue
        if shape.get("type") != "ply":
            fail(f"{where}: shape type not translated")
        pos, nrm, tri = read_ply(os.path.join(folder, value(shape, "string", "filename")))
        if value(shape, "boolean", "face_normals", "false") == "true":
            nrm = None
        if emitter is not None:
            if emitter.get("type") != "area" or max(albedo) > 0:
                fail(f"{where}: only black area emitters are translated")
            radiance = floats(value(emitter, "rgb", "radiance"))
            if rectangle(np, pos, tri) is not None and not mesh_lights:
                pos = pos + area_light(bpy, np, f"light{i}", pos, tri, radiance)
            else:
                mat = emission_material(bpy, radiance, f"emission{i}")
        add_mesh(bpy, np, f"mesh{i}", pos, nrm, tri, mat)
    for e in root.findall("emitter"):
        fail(f"{xml_path}: <emitter type=\"{e.get('type')}\"> is not translated "
             "(only area emitters on rectangles)")
    configure(scene, width, height, max_depth, rr_depth)
    return width, height, spp, max_depth


def configure(scene, width, height, max_depth, rr_depth):
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    bounces = max_depth - 2  # ember's -m minus one
    c.max_bounces = bounces
    for k in ("diffuse_bounces", "glossy_bounces", "transmission_bounces",
              "volume_bounces", "transparent_max_bounces"):
        setattr(c, k, bounces)
    c.min_light_bounces = max(rr_depth - 1, 0)
    c.caustics_reflective = c.caustics_refractive = True
    c.blur_glossy = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.use_animated_seed = False
    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.film_transparent = False
    r.use_persistent_data = True
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"
    r.image_settings.color_mode = "RGB"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0


def render(bpy, scene, spp, seed, path):
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.render.filepath = path
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - t0


def read_exr(bpy, np, path):
    """Linear RGB rows top to bottom (Blender's pixels run bottom to top)."""
    img = bpy.data.images.load(path, check_existing=False)
    img.colorspace_settings.is_data = True
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return px.reshape(h, w, 4)[::-1, :, :3].astype(np.float64)


def check(np, img, ref_img, ref_path):
    manifest = os.path.join(os.path.dirname(os.path.abspath(ref_path)), "manifest.json")
    entry = None
    if os.path.exists(manifest):
        with open(manifest) as f:
            for e in json.load(f).get("images", []):
                if e.get("file") == os.path.basename(ref_path):
                    entry = e
    ref_mean = entry["mean_rgb"] if entry else ref_img.reshape(-1, 3).mean(axis=0).tolist()
    ref_noise = entry["noise_rmse_per_pixel"] if entry else 0.0
    rmse = float(np.sqrt(((img - ref_img) ** 2).mean()))
    own_noise = math.sqrt(max(rmse ** 2 - ref_noise ** 2, 0.0))
    n = img.shape[0] * img.shape[1]
    mean = img.reshape(-1, 3).mean(axis=0).tolist()
    rel = [m / r - 1 for m, r in zip(mean, ref_mean)]
    tol = [0.01 + 4 * own_noise / math.sqrt(n) / r for r in ref_mean]
    ok = all(abs(d) <= t for d, t in zip(rel, tol))
    source = "manifest mean_rgb" if entry else "the reference image's mean"
    print(f"mean check: Cycles {', '.join(f'{m:.6f}' for m in mean)} against {source} "
          f"{', '.join(f'{m:.6f}' for m in ref_mean)}: "
          f"{', '.join(f'{100 * d:+.2f} %' for d in rel)} "
          f"(tolerance {', '.join(f'{100 * t:.2f} %' for t in tol)}): "
          f"{'OK' if ok else 'MISMATCH'}; RMSE {rmse:.5f}", file=sys.stderr)
    return {"mean_rgb": mean, "reference_mean_rgb": ref_mean, "mean_rel_diff": rel,
            "mean_tolerance": tol, "mean_ok": ok, "rmse": rmse}


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="the .xml written by `ember export --format mitsuba`")
    p.add_argument("--spp", type=int, help="samples per pixel (default: the file's)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--threads", type=int, default=0, help="0: all cores")
    p.add_argument("--pattern", default="AUTOMATIC",
                   help="Cycles sampling pattern: AUTOMATIC, TABULATED_SOBOL or BLUE_NOISE")
    p.add_argument("--out", help="the rendered image (OpenEXR); required unless --check-only")
    p.add_argument("--check-only", action="store_true",
                   help="only translate the scene: exit 0 if it can, 2 naming what it cannot")
    p.add_argument("--mesh-lights", action="store_true",
                   help="rectangular area lights as emissive meshes too (a check of that path)")
    p.add_argument("--reference", help="reference EXR to check the image against")
    a = p.parse_args()
    try:
        import bpy
        import numpy as np
    except ImportError as e:
        fail(f"cannot import bpy ({e}); scripts/cycles-env installs it")
    if not os.path.exists(a.scene):
        fail(f"{a.scene}: no such file")
    if not a.out and not a.check_only:
        fail("--out is required")
    width, height, spp, max_depth = build(bpy, np, a.scene, a.mesh_lights)
    if a.check_only:
        print(json.dumps({"translated": a.scene}), flush=True)
        return 0
    spp = a.spp or spp
    if spp < 2:
        fail("--spp must be at least 2 (a 1-spp render is subtracted as fixed cost)")
    scene = bpy.context.scene
    scene.cycles.sampling_pattern = a.pattern
    scene.render.threads_mode = "FIXED" if a.threads > 0 else "AUTO"
    if a.threads > 0:
        scene.render.threads = a.threads
    out = os.path.abspath(a.out)
    fixed_path = out + ".1spp.exr"
    render(bpy, scene, 1, a.seed, fixed_path)  # warm-up: kernels, scene sync
    t1 = render(bpy, scene, 1, a.seed, fixed_path)
    tn = render(bpy, scene, spp, a.seed, out)
    os.remove(fixed_path)
    seconds = max(tn - t1, 1e-9) * spp / (spp - 1)
    line = {"seconds": seconds, "samples_per_second": width * height * spp / seconds,
            "render_call_seconds": tn, "fixed_seconds": t1, "width": width,
            "height": height, "spp": spp, "max_bounces": max_depth - 2, "seed": a.seed,
            "pattern": scene.cycles.sampling_pattern, "renderer": f"Cycles {bpy.app.version_string}"}
    status = 0
    if a.reference:
        img = read_exr(bpy, np, out)
        ref = read_exr(bpy, np, a.reference)
        if ref.shape != img.shape:
            fail(f"{a.reference}: {ref.shape[1]}x{ref.shape[0]}, the render is {width}x{height}")
        line["check"] = check(np, img, ref, a.reference)
        status = 0 if line["check"]["mean_ok"] else 3
    print(json.dumps(line), flush=True)
    return status


if __name__ == "__main__":
    sys.exit(main())
