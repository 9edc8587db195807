"""Converts OpenEXR images to NumPy arrays, for scripts that run in Debian's python3 (which has no EXR
reader). Run inside headless Blender, which reads EXR:

  blender -b --python-exit-code 1 --python scripts/exr_to_npy.py -- LIST

LIST names one EXR per line; each NAME.exr becomes NAME.npy beside it: float32, height x width x 4
(RGBA), the top row first, the values as stored (scene-linear, no colour transform).
"""
import os
import sys

import bpy
import numpy as np

args = sys.argv[sys.argv.index("--") + 1:]
if len(args) != 1:
    raise SystemExit("exr_to_npy.py: usage: blender -b --python scripts/exr_to_npy.py -- LIST")
for path in open(args[0]).read().split("\n"):
    if not path:
        continue
    img = bpy.data.images.load(path)
    img.colorspace_settings.name = "Non-Color"  # the values as stored (scene-linear)
    w, h = img.size
    if w == 0 or h == 0:
        raise SystemExit("exr_to_npy.py: %s: Blender could not read it" % path)
    px = np.array(img.pixels[:], dtype=np.float32).reshape(h, w, 4)[::-1]  # Blender stores the bottom row first
    bpy.data.images.remove(img)
    out = path[:-4] + ".npy"
    tmp = out + ".tmp.npy"
    np.save(tmp, np.ascontiguousarray(px))
    os.replace(tmp, out)
