"""Blender side of tests/blender_sequence.sh (runs inside headless Blender).

  blender -b --factory-startup --python-exit-code 1 --python tests/blender_sequence.py -- \
      SCENE.blend FIRST COUNT OUT_DIR

Opens a .blend written by `cloudgen blender c_####.vdb --frames A:B`, checks its volume is a
Blender volume sequence (is_sequence, frame_start, frame_duration, velocity grid for motion blur)
that loads file c_000F.vdb at scene frame F for every frame, and renders the cloud's alpha mask
(transparent film, ground hidden) of the first and last frames to OUT_DIR/mask_F.png.
"""
import os
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
blend, first, count, out = argv[0], int(argv[1]), int(argv[2]), argv[3]
bpy.ops.wm.open_mainfile(filepath=blend)
scene = bpy.context.scene
vols = [o for o in scene.objects if o.type == "VOLUME"]
assert len(vols) == 1, [o.name for o in scene.objects]
vol = vols[0].data
assert vol.is_sequence, "the volume is not a sequence"
assert vol.frame_duration == count, (vol.frame_duration, count)
assert vol.frame_start == first, (vol.frame_start, first)
assert (scene.frame_start, scene.frame_end) == (first, first + count - 1), (scene.frame_start, scene.frame_end)
assert vol.velocity_grid == "velocity" and vol.velocity_unit == "SECOND", (vol.velocity_grid, vol.velocity_unit)
for f in range(first, first + count):
    scene.frame_set(f)
    vol.grids.unload() if hasattr(vol.grids, "unload") else None
    if not vol.grids.load():
        raise SystemExit(f"frame {f}: {vol.grids.error_message}")
    want = f"c_{f:04d}.vdb"
    got = os.path.basename(vol.grids.frame_filepath)
    assert got == want, f"scene frame {f} shows {got}, not {want}"
    names = [g.name for g in vol.grids]
    assert "density" in names and "velocity" in names, names
print(f"blender: frames {first}..{first + count - 1} play c_{first:04d}.vdb .. c_{first + count - 1:04d}.vdb, velocity grid set")
scene.render.film_transparent = True
scene.render.image_settings.color_mode = "RGBA"
scene.render.use_file_extension = False
for o in scene.objects:
    if o.type == "MESH":
        o.visible_camera = False
for f in (first, first + count - 1):
    scene.frame_set(f)
    scene.render.filepath = os.path.join(out, f"mask_{f}.png")
    bpy.ops.render.render(write_still=True)
    print("wrote", scene.render.filepath)
