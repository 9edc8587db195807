"""The path tracer against Blender's Cycles on one scene (docs/notes/accuracy.md, issue 10).

Run inside headless Blender by scripts/cycles_crosscheck.sh:
  blender -b --python-exit-code 1 --python scripts/cycles_crosscheck.py -- render SCENE.blend OUT.exr SAMPLES BOUNCES SEED SUN.json STEP_RATE
      re-lights the scene `cloudgen blender` wrote so that only the sun lights the cloud (black
      world, no ground, transparent film: each pixel is the cloud's own radiance), with the sun
      colour and strength of SUN.json (`cloudviewer --lighting-json`), and renders it to a float EXR;
  blender -b --python-exit-code 1 --python scripts/cycles_crosscheck.py -- compare PT.exr BG.exr T.exr C0.exr C1.exr [MAX_DIFF]
      the path tracer's cloud radiance (its image minus the transmittance times the background)
      against the two Cycles renders on the pixels both see as cloud: mean luminance, its ratio and
      each side's noise on that mean (the two Cycles seeds; the path tracer's NAME.stderr.exr).
"""
import json
import math
import sys

import bpy
import numpy as np

args = sys.argv[sys.argv.index("--") + 1:]


def load(path):
    img = bpy.data.images.load(path)
    img.colorspace_settings.name = "Non-Color"  # the values as stored (scene-linear)
    w, h = img.size
    px = np.array(img.pixels[:], dtype=np.float64).reshape(h, w, 4)
    bpy.data.images.remove(img)
    return px


if args[0] == "render":
    blend, out, samples, bounces, seed, sun_json = args[1], args[2], int(args[3]), int(args[4]), int(args[5]), args[6]
    step_rate = float(args[7])
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    L = json.load(open(sun_json))
    for o in list(scene.objects):
        if o.type == "MESH":  # the ground plane
            bpy.data.objects.remove(o)
        elif o.type == "LIGHT":
            o.data.energy = L["sun_intensity"]
            o.data.color = L["sun_color"]
            o.data.angle = 0.0  # a direction, as the path tracer's sun
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world
    scene.render.film_transparent = True
    cy = scene.cycles
    cy.samples = samples
    cy.seed = seed
    cy.volume_bounces = bounces
    cy.max_bounces = bounces + 4
    cy.transparent_max_bounces = 64
    # The path tracer samples each pixel's centre; Cycles' narrowest filter is its box (one pixel:
    # its width setting, 0.01 or 1, gives the same image), not the default 1.5-pixel Blackman-Harris.
    cy.pixel_filter_type = "BOX"
    cy.volume_step_rate = step_rate  # Cycles ray-marches heterogeneous volumes: steps of rate x one voxel
    cy.volume_max_steps = 4096
    scene.use_nodes = False  # no compositor tone map: scene-linear radiance
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_mode = "RGBA"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = out
    bpy.ops.render.render(write_still=True)
elif args[0] == "compare":
    pt, bg, tr, c0, c1 = (load(p) for p in args[1:6])
    pt_err = load(args[1][:-4] + ".stderr.exr")
    lum = np.array([0.2126, 0.7152, 0.0722])
    cloud_pt = pt[..., :3] - tr[..., :3] * bg[..., :3]
    mask = (tr[..., 0] < 0.9) & (c0[..., 3] > 0.1) & (c1[..., 3] > 0.1)
    n = int(mask.sum())
    a = (cloud_pt @ lum)[mask]
    b0, b1 = (c0[..., :3] @ lum)[mask], (c1[..., :3] @ lum)[mask]
    b = (b0 + b1) / 2
    # Noise of each mean: Cycles from its two seeds, the path tracer from its per-pixel standard error.
    cy_noise = float(np.abs(b0.mean() - b1.mean()) / 2)
    pt_noise = float(np.sqrt(((pt_err[..., :3] @ lum)[mask] ** 2).sum()) / n)
    ratio = a.mean() / b.mean()
    rel_sigma = math.hypot(pt_noise / a.mean(), cy_noise / b.mean())
    print("cloud pixels: %d" % n)
    print("mean cloud luminance: path tracer %.5f, Cycles %.5f, ratio %.4f (%+.2f%%), combined noise %.2f%%" % (
        a.mean(), b.mean(), ratio, 100 * (ratio - 1), 100 * rel_sigma))
    # Per pixel: the RMS difference against what the two renderers' noise alone would give.
    pt_pixel = (pt_err[..., :3] @ lum)[mask]
    expected = float(np.sqrt((pt_pixel ** 2 + ((b0 - b1) / 2) ** 2).mean()))
    print("noise on the means: path tracer %.2e, Cycles %.2e; per-pixel RMS difference %.4f (relative %.3f), "
          "expected from the noise alone %.4f" % (pt_noise, cy_noise, float(np.sqrt(((a - b) ** 2).mean())),
                                                  float(np.sqrt(((a - b) ** 2).mean()) / b.mean()), expected))
    if len(args) > 6:
        bound = float(args[6])
        if n < 100 or not abs(ratio - 1) <= bound:
            print("FAIL: %d cloud pixels, the means differ by %.2f%% (bound %.1f%%)" % (n, 100 * abs(ratio - 1), 100 * bound))
else:
    raise SystemExit("cycles_crosscheck.py: render or compare")
