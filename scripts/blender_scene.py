"""Builds the Blender scene of a cloudgen VDB (run by `cloudgen blender` inside headless Blender).

  blender -b --factory-startup --python-exit-code 1 --python scripts/blender_scene.py -- SCENE.json

SCENE.json is written by `cloudgen blender` (cloudgen/cli/blender_cmd.cpp), which computes every
number from the VDB's metadata and cloudgen/include/cloudgen/view.h, the definitions the viewer
uses: camera, sun, world, material and tone map, all in Blender's z-up world. This script only
turns them into Blender data, saves the .blend and optionally renders it with Cycles. See
docs/blender.md for what each setting is and where Cycles and the viewer differ.
"""
import json
import math
import sys

import bpy
from mathutils import Vector

scene_file = sys.argv[sys.argv.index("--") + 1]
with open(scene_file) as f:
    S = json.load(f)

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.name = "cloud"

# ---------------------------------------------------------------- volume
vol = bpy.data.volumes.new("cloud")
vol.filepath = S["vdb"]
if not vol.grids.load():
    raise SystemExit(f"Blender could not load {S['vdb']}: {vol.grids.error_message}")
names = [g.name for g in vol.grids]
if "density" not in names:
    raise SystemExit(f"{S['vdb']}: no grid 'density' (grids: {names})")
vol.render.precision = "FULL"  # NanoVDB half/variable precision would quantise the density
if "velocity" in names:  # metres per second (cloudgen writes dD/dt): Cycles' motion blur reads it
    vol.velocity_grid = "velocity"
    vol.velocity_unit = "SECOND"
    vol.velocity_scale = 1.0
vol.render.space = "OBJECT"
vol.render.step_size = 0.0  # auto: one voxel, times Cycles' step rate
obj = bpy.data.objects.new("cloud", vol)
scene.collection.objects.link(obj)
Q = S.get("sequence")
if Q:
    # A VDB sequence (cloud_0000.vdb ... as `cloudgen generate --frames` names it), set up after the
    # first file's load above (a volume outside the scene would load frame 0). Blender swaps the
    # file name's frame number: scene frame F shows file (F - frame_start + 1) + frame_offset, so
    # frame_start = A and frame_offset = A - 1 show file F at scene frame F.
    vol.is_sequence = True
    vol.frame_start = Q["first"]
    vol.frame_offset = Q["first"] - 1
    vol.frame_duration = Q["count"]
    vol.sequence_mode = "REPEAT" if Q["loop"] else "CLIP"
    scene.frame_start = Q["first"]
    scene.frame_end = Q["first"] + Q["count"] - 1
    fps = float(Q["fps"])
    scene.render.fps = max(1, round(fps))
    scene.render.fps_base = scene.render.fps / fps
    scene.frame_set(Q["render_frame"])
# A y-up file stands upright by +90 degrees about x; a z-up file is upright already.
obj.rotation_euler = (math.pi / 2, 0.0, 0.0) if S["up"] == "y" else (0.0, 0.0, 0.0)
# OpenVDB's convention puts voxel (i,j,k)'s value at index point (i,j,k), and Blender's object
# bounds follow it, but Cycles in Blender 3.4 renders that value at index (i+0.5, j+0.5, k+0.5):
# measured with a one-voxel grid (tests/blender_roundtrip.sh), the cloud sits half a voxel off
# along every index axis. Shift the object back by half a voxel so Cycles puts it where the file
# (and the viewer) say. Newer Blender versions are not measured; the test tells.
# The index axes (x, y, z) run along Blender's (+x, +z, -y) for both up axes (a z-up file's grid
# transform turns them so; a y-up file's object rotation does), so -half a voxel along each index
# axis is (-h, +h, -h) in the world.
h = 0.5 * S["voxel_size"] if bpy.app.version < (3, 5, 0) else 0.0
obj.location = (-h, h, -h)
obj["cycles_voxel_shift"] = list(obj.location)

# ---------------------------------------------------------------- material
M = S["material"]
mat = bpy.data.materials.new("cloud")
mat.use_nodes = True
nt = mat.node_tree
for n in list(nt.nodes):
    nt.nodes.remove(n)
out = nt.nodes.new("ShaderNodeOutputMaterial")
pv = nt.nodes.new("ShaderNodeVolumePrincipled")
pv.inputs["Color"].default_value = (M["albedo"], M["albedo"], M["albedo"], 1.0)
pv.inputs["Absorption Color"].default_value = (0.0, 0.0, 0.0, 1.0)
pv.inputs["Anisotropy"].default_value = M["anisotropy"]
DENSITY = M.get("density_grid", "density")  # a level of detail: density_level_N (cloudgen blender --level)
if DENSITY not in names:
    raise SystemExit(f"{S['vdb']}: no grid '{DENSITY}' (grids: {names})")
pv.inputs["Density Attribute"].default_value = DENSITY
nt.links.new(pv.outputs["Volume"], out.inputs["Volume"])


def math_node(op, a, b=None, clamp=False):
    n = nt.nodes.new("ShaderNodeMath")
    n.operation = op
    n.use_clamp = clamp
    for i, v in enumerate((a, b)):
        if v is None:
            continue
        if isinstance(v, (int, float)):
            n.inputs[i].default_value = v
        else:
            nt.links.new(v, n.inputs[i])
    return n.outputs[0]


if M["erosion"] > 0 and all(g in names for g in M["detail_grids"]):
    # The viewer's erosion (viewer/shaders/cloud_functions.glsl, cloud_density): detail =
    # 0.625 G + 0.25 B + 0.125 A, inverted near the base (h * 5 < 1), e = erosion * detail,
    # eroded = clamp((base - e) / (1 - e)). Principled Volume multiplies Density by the density
    # attribute (base), so Density gets extinction * eroded / base.
    def attr(name):
        a = nt.nodes.new("ShaderNodeAttribute")
        a.attribute_name = name
        return a.outputs["Fac"]

    g, b, a = (attr(n) for n in M["detail_grids"])
    detail = math_node("ADD", math_node("ADD", math_node("MULTIPLY", g, 0.625), math_node("MULTIPLY", b, 0.25)),
                       math_node("MULTIPLY", a, 0.125))
    tc = nt.nodes.new("ShaderNodeTexCoord")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    nt.links.new(tc.outputs["Object"], sep.inputs[0])
    height = sep.outputs["Z" if S["up"] == "z" else "Y"]
    h = math_node("DIVIDE", math_node("SUBTRACT", height, M["box_bottom"]), M["box_height"])
    t = math_node("MULTIPLY", h, 5.0, clamp=True)
    # mix(1 - d, d, t) = (1 - d) + t (2 d - 1)
    detail = math_node("ADD", math_node("SUBTRACT", 1.0, detail), math_node("MULTIPLY", t, math_node("SUBTRACT", math_node("MULTIPLY", detail, 2.0), 1.0)))
    e = math_node("MULTIPLY", detail, M["erosion"])
    base = math_node("DIVIDE", attr(DENSITY), M["grid_scale"])  # normalised density (physical units: / extinction)
    eroded = math_node("DIVIDE", math_node("SUBTRACT", base, e), math_node("MAXIMUM", math_node("SUBTRACT", 1.0, e), 1e-4), clamp=True)
    ratio = math_node("DIVIDE", eroded, math_node("MAXIMUM", base, 1e-6))
    nt.links.new(math_node("MULTIPLY", ratio, M["density"]), pv.inputs["Density"])
else:
    pv.inputs["Density"].default_value = M["density"]
vol.materials.append(mat)

# ---------------------------------------------------------------- camera
C = S["camera"]
cam_data = bpy.data.cameras.new("camera")
cam_data.sensor_fit = "VERTICAL"
cam_data.angle_y = math.radians(C["fov_y_deg"])
cam_data.clip_start = 0.5
cam_data.clip_end = 1e6
cam = bpy.data.objects.new("camera", cam_data)
scene.collection.objects.link(cam)
cam.location = C["eye"]
cam.rotation_euler = (Vector(C["target"]) - Vector(C["eye"])).to_track_quat("-Z", "Y").to_euler()
scene.camera = cam

# ---------------------------------------------------------------- sun
L = S["sun"]
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = L["strength"]  # irradiance, W/m^2: the viewer's sun_intensity (no pi)
sun.data.color = L["color"]
sun.data.angle = math.radians(0.53)
sun.rotation_euler = (-Vector(L["direction"])).to_track_quat("-Z", "Y").to_euler()  # light travels along -Z
scene.collection.objects.link(sun)

# ---------------------------------------------------------------- world
W = S["world"]
world = bpy.data.worlds.new("sky")
world.use_nodes = True
wt = world.node_tree
for n in list(wt.nodes):
    wt.nodes.remove(n)
wout = wt.nodes.new("ShaderNodeOutputWorld")
ambient = wt.nodes.new("ShaderNodeBackground")  # what lights the cloud: the viewer's ambient
ambient.inputs["Color"].default_value = (*W["ambient"], 1.0)
ambient.inputs["Strength"].default_value = 1.0
# What the camera sees: the viewer's sky gradient (sky_radiance without the sun disc).
tc = wt.nodes.new("ShaderNodeTexCoord")
sep = wt.nodes.new("ShaderNodeSeparateXYZ")
wt.links.new(tc.outputs["Generated"], sep.inputs[0])
up = wt.nodes.new("ShaderNodeMath")
up.operation = "POWER"
up.use_clamp = True
wt.links.new(sep.outputs["Z"], up.inputs[0])
up.inputs[1].default_value = 0.5  # sqrt(clamp(z)); pow of a negative base gives 0
grad = wt.nodes.new("ShaderNodeMixRGB")
wt.links.new(up.outputs[0], grad.inputs["Fac"])
grad.inputs["Color1"].default_value = (*W["horizon"], 1.0)
grad.inputs["Color2"].default_value = (*W["zenith"], 1.0)
below = wt.nodes.new("ShaderNodeMath")
below.operation = "LESS_THAN"
wt.links.new(sep.outputs["Z"], below.inputs[0])
below.inputs[1].default_value = 0.0
sky = wt.nodes.new("ShaderNodeMixRGB")
wt.links.new(below.outputs[0], sky.inputs["Fac"])
wt.links.new(grad.outputs[0], sky.inputs["Color1"])
sky.inputs["Color2"].default_value = (*[0.6 * c for c in W["horizon"]], 1.0)
sky_bg = wt.nodes.new("ShaderNodeBackground")
wt.links.new(sky.outputs[0], sky_bg.inputs["Color"])
lp = wt.nodes.new("ShaderNodeLightPath")
mix = wt.nodes.new("ShaderNodeMixShader")
wt.links.new(lp.outputs["Is Camera Ray"], mix.inputs["Fac"])
wt.links.new(ambient.outputs[0], mix.inputs[1])
wt.links.new(sky_bg.outputs[0], mix.inputs[2])
wt.links.new(mix.outputs[0], wout.inputs["Surface"])
scene.world = world

# ---------------------------------------------------------------- ground
G = S["ground"]
if G["enabled"]:
    e = G["half_extent"]
    mesh = bpy.data.meshes.new("ground")
    mesh.from_pydata([(-e, -e, G["height"]), (e, -e, G["height"]), (e, e, G["height"]), (-e, e, G["height"])], [],
                     [(0, 1, 2, 3)])
    ground = bpy.data.objects.new("ground", mesh)
    gm = bpy.data.materials.new("ground")
    gm.use_nodes = True
    bsdf = gm.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*G["color"], 1.0)
    bsdf.inputs["Roughness"].default_value = 1.0
    bsdf.inputs["Specular"].default_value = 0.0
    mesh.materials.append(gm)
    scene.collection.objects.link(ground)

# ---------------------------------------------------------------- Cycles
R = S["render"]
scene.render.engine = "CYCLES"
cy = scene.cycles
cy.device = "CPU"
cy.samples = R["samples"]
cy.use_denoising = False  # Debian builds Blender without OpenImageDenoise
cy.use_adaptive_sampling = False
cy.max_bounces = R["max_bounces"]
cy.volume_bounces = R["volume_bounces"]
cy.diffuse_bounces = 2
cy.glossy_bounces = 0
cy.transmission_bounces = 0
cy.transparent_max_bounces = 8
cy.volume_step_rate = R["volume_step_rate"]
cy.volume_preview_step_rate = R["volume_step_rate"]
cy.volume_max_steps = R["volume_max_steps"]
cy.seed = 0
scene.render.resolution_x, scene.render.resolution_y = R["width"], R["height"]
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "PNG"
scene.render.image_settings.color_mode = "RGB"  # sky and ground cover the frame
scene.render.image_settings.compression = 90
# The viewer's tone map, done in the compositor: x * exposure, Reinhard x / (1 + x) per channel,
# then Blender's Standard view transform encodes sRGB like the viewer.
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
scene.view_settings.exposure = 0.0
scene.view_settings.gamma = 1.0
scene.use_nodes = True
ct = scene.node_tree
for n in list(ct.nodes):
    ct.nodes.remove(n)
rl = ct.nodes.new("CompositorNodeRLayers")
comp = ct.nodes.new("CompositorNodeComposite")
split = ct.nodes.new("CompositorNodeSepRGBA")
join = ct.nodes.new("CompositorNodeCombRGBA")
ct.links.new(rl.outputs["Image"], split.inputs[0])
for ch in "RGB":
    m = ct.nodes.new("CompositorNodeMath")
    m.operation = "MULTIPLY"
    ct.links.new(split.outputs[ch], m.inputs[0])
    m.inputs[1].default_value = S["tonemap"]["exposure"]
    if S["tonemap"]["operator"] == "reinhard":
        d = ct.nodes.new("CompositorNodeMath")
        d.operation = "ADD"
        ct.links.new(m.outputs[0], d.inputs[0])
        d.inputs[1].default_value = 1.0
        q = ct.nodes.new("CompositorNodeMath")
        q.operation = "DIVIDE"
        ct.links.new(m.outputs[0], q.inputs[0])
        ct.links.new(d.outputs[0], q.inputs[1])
        m = q
    ct.links.new(m.outputs[0], join.inputs[ch])
ct.links.new(split.outputs["A"], join.inputs["A"])
ct.links.new(join.outputs[0], comp.inputs["Image"])

# Saved beside the final .blend (a temporary name in the same folder), so the relative path holds.
vol.filepath = S["vdb_relative"]
scene.render.use_file_extension = False  # the PNG goes to a temporary name first
# No "NAME.blend1" backup: cloudgen hands Blender an empty staged temporary to save over, and
# Blender's save versions would keep it beside the output as an empty "...1" file.
bpy.context.preferences.filepaths.save_version = 0
bpy.ops.wm.save_as_mainfile(filepath=S["blend"], relative_remap=False)
print(f"cloudgen blender: wrote {S['blend']}")
if S.get("render_png"):
    scene.render.filepath = S["render_png"]
    bpy.ops.render.render(write_still=True)
    print(f"cloudgen blender: wrote {S['render_png']}")
