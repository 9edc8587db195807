"""Blender side of tests/blender_roundtrip.sh (runs inside headless Blender).

  blender -b --factory-startup --python-exit-code 1 --python tests/blender_roundtrip.py -- \
      check SCENE.blend MASK.png VOXEL XMIN YMIN ZMIN XMAX YMAX ZMAX FULL.vdb HEIGHT
      compare VIEWER_T.png CYCLES_MASK.png [VIEWER.png CYCLES.png]
      mask SCENE.blend MASK.png
      centroid VIEWER_T.png CYCLES_MASK.png TOLERANCE_PX

check: reloads a .blend written by `cloudgen blender`, checks it holds the volume (grid
`density` loaded, upright: its world bounds equal the z-up box given, computed by OpenVDB's own
reader), a Principled Volume material, a sun and the scene camera; imports FULL.vdb as File >
Import does (no rotation) and checks its box is HEIGHT metres along z; then renders the cloud's
alpha mask (transparent film, ground hidden from the camera) to MASK.png at the scene's size.

compare: the cloud masks of the viewer (VIEWER_T.png: render.output=transmittance, clamp tone
map, exposure 1; cloud where T < 0.9) and of Cycles (alpha > 0.1); prints their IoU, both bounding
boxes in pixels and, given the two pictures, the mean luminance of the cloud pixels in each.
Exits non-zero when the IoU is below 0.7.

mask: only the alpha-mask render of `check`. centroid: the transmittance-weighted centroids of
the two masks (a one-voxel grid) must lie within TOLERANCE_PX of each other.
"""
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
mode = argv[0]


def pixels(path):
    img = bpy.data.images.load(path, check_existing=False)
    img.colorspace_settings.name = "Non-Color"  # the stored (sRGB-encoded) values, unconverted
    w, h = img.size
    px = list(img.pixels)
    return w, h, [px[i:i + 4] for i in range(0, len(px), 4)]


def bbox(mask, w):
    idx = [i for i, m in enumerate(mask) if m]
    if not idx:
        return None
    xs = [i % w for i in idx]
    ys = [i // w for i in idx]
    return (min(xs), min(ys), max(xs), max(ys))


def render_mask(scene, path):
    """The cloud's alpha alone: transparent film, meshes (the ground) hidden from the camera."""
    scene.render.film_transparent = True
    scene.render.image_settings.color_mode = "RGBA"
    for o in scene.objects:
        if o.type == "MESH":
            o.visible_camera = False
    scene.render.filepath = path
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True)
    print("wrote", path)


if mode == "check":
    blend, mask_png, voxel = argv[1], argv[2], float(argv[3])
    want = [float(v) for v in argv[4:10]]
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    vols = [o for o in scene.objects if o.type == "VOLUME"]
    assert len(vols) == 1, f"expected one volume object, got {[o.name for o in scene.objects]}"
    obj = vols[0]
    vol = obj.data
    if not vol.grids.load():
        raise SystemExit(f"the scene's volume does not load: {vol.grids.error_message} ({vol.filepath})")
    names = [g.name for g in vol.grids]
    assert "density" in names, names
    mats = [m for m in vol.materials if m and m.use_nodes]
    assert mats, "the volume has no material"
    pv = [n for n in mats[0].node_tree.nodes if n.bl_idname == "ShaderNodeVolumePrincipled"]
    assert pv, "the material has no Principled Volume"
    print("principled volume: density", pv[0].inputs["Density"].default_value, "linked",
          pv[0].inputs["Density"].is_linked, "anisotropy", pv[0].inputs["Anisotropy"].default_value)
    suns = [o for o in scene.objects if o.type == "LIGHT" and o.data.type == "SUN"]
    assert suns, "no sun lamp"
    assert scene.camera is not None and scene.camera.type == "CAMERA", "no scene camera"
    bpy.context.view_layer.update()
    # Less the half-voxel shift the scene applies for Cycles (scripts/blender_scene.py).
    shift = __import__("mathutils").Vector(obj.get("cycles_voxel_shift", (0.0, 0.0, 0.0)))
    corners = [obj.matrix_world @ __import__("mathutils").Vector(c) - shift for c in obj.bound_box]
    got = [min(c[a] for c in corners) for a in range(3)] + [max(c[a] for c in corners) for a in range(3)]
    print("blender world bounds:", [round(v, 3) for v in got], "openvdb (z up):", want)
    for g, w in zip(got, want):
        if abs(g - w) > 1e-3 * voxel:
            raise SystemExit(f"bounds differ: blender {got} vs openvdb {want}")
    full_path, full_height = argv[10], float(argv[11])
    full = bpy.data.volumes.new("full")
    full.filepath = full_path
    if not full.grids.load():
        raise SystemExit(f"{full_path}: {full.grids.error_message}")
    fobj = bpy.data.objects.new("full", full)
    scene.collection.objects.link(fobj)
    bpy.context.view_layer.update()
    zs = [(fobj.matrix_world @ __import__("mathutils").Vector(c))[2] for c in fobj.bound_box]
    height = max(zs) - min(zs) + voxel  # bounds span voxel centres
    if abs(height - full_height) > 1e-3 * voxel:
        raise SystemExit(f"imported as it is, the preset's box is {height} m along z, not its height {full_height} m")
    print(f"upright: the preset's {height:.0f} m height runs along z")
    bpy.data.objects.remove(fobj)
    render_mask(scene, mask_png)
elif mode == "mask":
    bpy.ops.wm.open_mainfile(filepath=argv[1])
    render_mask(bpy.context.scene, argv[2])
elif mode == "centroid":
    # Where each renderer puts a one-voxel grid: the cloud-weighted centroid of each mask.
    vw, vh, vpx = pixels(argv[1])
    cw, ch, cpx = pixels(argv[2])
    tol = float(argv[3])
    srgb_to_lin = lambda c: c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4
    def centroid(weights, w):
        total = sum(weights)
        return (sum(a * (i % w) for i, a in enumerate(weights)) / total, sum(a * (i // w) for i, a in enumerate(weights)) / total)
    v = centroid([1.0 - srgb_to_lin(p[0]) for p in vpx], vw)
    c = centroid([p[3] for p in cpx], cw)
    print(f"one voxel: viewer centroid ({v[0]:.2f}, {v[1]:.2f}) px, cycles ({c[0]:.2f}, {c[1]:.2f}) px, image centre {(vw - 1) / 2}")
    if max(abs(v[0] - c[0]), abs(v[1] - c[1])) > tol:
        raise SystemExit(f"Cycles and the viewer place the voxel more than {tol} px apart")
elif mode == "compare":
    vw, vh, vpx = pixels(argv[1])
    cw, ch, cpx = pixels(argv[2])
    if (vw, vh) != (cw, ch):
        raise SystemExit(f"sizes differ: viewer {vw}x{vh}, cycles {cw}x{ch}")
    srgb_09 = 1.055 * 0.9 ** (1 / 2.4) - 0.055  # T = 0.9 as the viewer's PNG stores it
    vmask = [p[0] < srgb_09 for p in vpx]
    cmask = [p[3] > 0.1 for p in cpx]
    inter = sum(1 for a, b in zip(vmask, cmask) if a and b)
    union = sum(1 for a, b in zip(vmask, cmask) if a or b)
    iou = inter / union if union else 0.0
    print(f"cloud pixels: viewer {sum(vmask)}, cycles {sum(cmask)} of {vw * vh}; IoU {iou:.3f}")
    print(f"bounding box (x0, y0, x1, y1; y up): viewer {bbox(vmask, vw)}, cycles {bbox(cmask, cw)}")
    if len(argv) >= 5:
        for name, path in (("viewer", argv[3]), ("cycles", argv[4])):
            w, h, px = pixels(path)
            both = [i for i in range(w * h) if vmask[i] and cmask[i]]
            lum = [0.2126 * px[i][0] + 0.7152 * px[i][1] + 0.0722 * px[i][2] for i in both]
            print(f"{name}: mean sRGB luminance of the cloud pixels both masks share {sum(lum) / max(1, len(lum)):.3f}")
    if sum(cmask) < vw * vh // 100:
        raise SystemExit("the Cycles render is blank: the cloud is not visible")
    if iou < 0.7:
        raise SystemExit(f"IoU {iou:.3f} < 0.7: Cycles and the viewer do not frame the cloud alike")
    print("masks agree")
else:
    raise SystemExit(f"unknown mode {mode}")
