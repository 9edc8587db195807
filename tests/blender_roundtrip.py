"""Blender round trip of a cloudgen VDB (run by tests/blender_roundtrip.sh inside headless Blender).

  blender -b --factory-startup --python-exit-code 1 --python tests/blender_roundtrip.py -- \
      VOLUME.vdb OUT.png XMIN YMIN ZMIN XMAX YMAX ZMAX

Loads the VDB as a volume object (what File > Import > OpenVDB does), checks that Blender finds the
grid `density` and that the object's bounds match the world bounding box OpenVDB reports (within
one voxel; Blender's bounds are the voxel centres of the union of all grids), then renders a tiny Cycles image with a Principled Volume material and checks the cloud
is visible against the background.
"""
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
vdb, out_png = argv[0], argv[1]
want = [float(v) for v in argv[2:8]]
voxel = float(argv[8])

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene

vol = bpy.data.volumes.new("cloud")
vol.filepath = vdb
obj = bpy.data.objects.new("cloud", vol)
scene.collection.objects.link(obj)
if not vol.grids.load():
    raise SystemExit(f"Blender could not load {vdb}: {vol.grids.error_message}")
names = [g.name for g in vol.grids]
print("grids:", names)
if "density" not in names:
    raise SystemExit(f"no grid 'density' in {names}")
dens = vol.grids["density"]
print("density grid:", dens.data_type, "channels", dens.channels)

bpy.context.view_layer.update()
xs = [c[0] for c in obj.bound_box]
ys = [c[1] for c in obj.bound_box]
zs = [c[2] for c in obj.bound_box]
got = [min(xs), min(ys), min(zs), max(xs), max(ys), max(zs)]
print("blender bounds:", got, "openvdb bounds:", want)
for g, w in zip(got, want):
    if abs(g - w) > 1.01 * voxel:
        raise SystemExit(f"bounds differ by more than one voxel: blender {got} vs openvdb {want}")

# Material: Principled Volume reads the 'density' attribute by default.
mat = bpy.data.materials.new("cloud")
mat.use_nodes = True
nt = mat.node_tree
for n in list(nt.nodes):
    nt.nodes.remove(n)
outn = nt.nodes.new("ShaderNodeOutputMaterial")
pv = nt.nodes.new("ShaderNodeVolumePrincipled")
pv.inputs["Density"].default_value = 0.05
nt.links.new(pv.outputs["Volume"], outn.inputs["Volume"])
vol.materials.append(mat)

# cloudgen writes y-up (the OpenVDB/Houdini convention); in Z-up Blender the user rotates the
# object +90 degrees about X (docs/blender.md), so local (x, y, z) lands at world (x, -z, y).
import math
obj.rotation_euler = (math.pi / 2, 0.0, 0.0)
cx, cy, cz = [(want[i] + want[i + 3]) / 2 for i in range(3)]
size = max(want[3] - want[0], want[4] - want[1], want[5] - want[2])
centre = (cx, -cz, cy)
cam_data = bpy.data.cameras.new("cam")
cam = bpy.data.objects.new("cam", cam_data)
scene.collection.objects.link(cam)
scene.camera = cam
# Look at the cloud from the side (from -Y), slightly above its middle.
cam.location = (centre[0], centre[1] - 2.0 * size, centre[2] + 0.2 * size)
direction = tuple(centre[i] - cam.location[i] for i in range(3))
from mathutils import Vector
cam.rotation_euler = Vector(direction).to_track_quat("-Z", "Y").to_euler()
cam_data.clip_end = 10 * size

sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 4.0
sun.rotation_euler = (0.6, 0.2, 0.8)
scene.collection.objects.link(sun)
world = bpy.data.worlds.new("w")
world.color = (0.05, 0.07, 0.12)
scene.world = world

scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 32
scene.cycles.use_denoising = False  # Debian builds Blender without OpenImageDenoise
scene.cycles.volume_step_rate = 4.0
scene.render.resolution_x = 160
scene.render.resolution_y = 100
scene.render.resolution_percentage = 100
scene.render.filepath = out_png
scene.render.image_settings.file_format = "PNG"
bpy.ops.render.render(write_still=True)

img = bpy.data.images.load(out_png)
px = list(img.pixels)
lum = [0.2126 * px[i] + 0.7152 * px[i + 1] + 0.0722 * px[i + 2] for i in range(0, len(px), 4)]
bg = sorted(lum)[len(lum) // 10]
bright = sum(1 for v in lum if v > bg + 0.05)
print(f"render: background {bg:.3f}, max {max(lum):.3f}, {bright} of {len(lum)} pixels brighter than background")
if bright < len(lum) // 50:
    raise SystemExit("the render is blank: the cloud is not visible")
print("blender round trip OK")
