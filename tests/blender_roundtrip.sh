#!/usr/bin/env bash
# CTest: cloudgen's VDB read by OpenVDB's own Python binding (placement, up axis), then
# `cloudgen blender` builds a scene that Blender reloads and renders, compared with the viewer's
# default view of the same file. Usage: blender_roundtrip.sh BUILD_BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
py=/usr/bin/python3
blender_py() { blender -b --factory-startup --python-exit-code 1 --python "$src/tests/blender_roundtrip.py" -- "$@" 2>&1 |
  grep -vE "^(Fra:|Blender quit|Read blend|Saved|Blender 3|Read prefs|Color management)" | tail -20; return "${PIPESTATUS[0]}"; }

# 1. Placement, OpenVDB's convention: a one-voxel grid's voxel centre is its index point through
#    the transform. Voxel [100,110] x [200,210] x [300,310] (y up) has its centre at (105, 205, 305);
#    with up = z it is (105, -305, 205). The raw sidecar's origin is the same voxel's min corner.
one=(--set 'resolution=[1,1,1]' --set threshold=0 --set density_scale=1000 --set 'origin=[100,200,300]' --set voxel_size=10)
"$bin/cloudgen" generate tiny -q "${one[@]}" -o "$tmp/one-z.vdb"
"$bin/cloudgen" generate tiny -q "${one[@]}" --up y -o "$tmp/one-y.vdb" -o "$tmp/one.raw"
$py - "$tmp" <<'PY'
import json, sys, pyopenvdb as vdb
d = sys.argv[1]
for up, want in (("z", (105, -305, 205)), ("y", (105, 205, 305))):
    g = vdb.read(f"{d}/one-{up}.vdb", "density")
    (lo, hi) = g.evalActiveVoxelBoundingBox()
    assert lo == hi, (lo, hi)
    got = g.transform.indexToWorld(lo)
    assert all(abs(a - b) < 1e-9 for a, b in zip(got, want)), (up, got, want)
side = json.load(open(f"{d}/one.json"))
centre = [o + 0.5 * side["voxel_size"] for o in side["origin"]]
assert centre == [105, 205, 305], centre
print("placement: one voxel lands at OpenVDB's indexToWorld in both frames and in the sidecar")
PY

# 2. The tiny preset, up = z (default) and up = y: OpenVDB's reader gives the y-up file's box; the
#    z-up file must hold the same box turned upright, (x, y, z) -> (x, -z, y).
"$bin/cloudgen" generate tiny -q -o "$tmp/tiny.vdb"
"$bin/cloudgen" generate tiny -q --up y -o "$tmp/tiny-y.vdb"
read -r bounds voxel < <($py - "$tmp/tiny.vdb" "$tmp/tiny-y.vdb" <<'PY'
import sys, pyopenvdb as vdb
def world_box(path):
    grids, meta = vdb.readAll(path)
    g = {x.name: x for x in grids}["density"]
    assert g.gridClass == vdb.GridClass.FOG_VOLUME, g.gridClass
    assert not str(meta.get("creator", "")).startswith("Houdini")
    lo_v, hi_v = g.evalMinMax()
    assert 0.0 <= lo_v and hi_v <= 1.0, (lo_v, hi_v)
    # Blender's object bounds span the voxel centres of the leaf nodes (8^3) holding any grid's
    # active voxels.
    los, his = zip(*(x.evalActiveVoxelBoundingBox() for x in grids))
    i0 = [min(c[a] for c in los) // 8 * 8 for a in range(3)]
    i1 = [max(c[a] for c in his) // 8 * 8 + 7 for a in range(3)]
    a, b = g.transform.indexToWorld(i0), g.transform.indexToWorld(i1)
    return [min(a[k], b[k]) for k in range(3)] + [max(a[k], b[k]) for k in range(3)], g.transform.voxelSize()[0], g
z, vs, gz = world_box(sys.argv[1])
y, _, gy = world_box(sys.argv[2])
assert gz.metadata["up_axis"] == "z" and gy.metadata["up_axis"] == "y"
turned = [y[0], -y[5], y[1], y[3], -y[2], y[4]]
assert all(abs(p - q) < 1e-6 for p, q in zip(z, turned)), (z, turned)
print(",".join(f"{v:.6f}" for v in z), vs)
PY
)
# The same preset with every voxel non-zero (threshold 0): its box is the preset's whole box, whose
# height, 32 voxels of 25 m, must run along z when Blender imports the file as it is.
"$bin/cloudgen" generate tiny -q --set threshold=0 --set density_scale=1000 --set export.vdb.detail=false -o "$tmp/full.vdb"
echo "openvdb: z-up world bbox $bounds, voxel $voxel"

# 3. `cloudgen blender`: scene + a tiny Cycles render; Blender reloads it, checks it and renders
#    the cloud's alpha mask at the same size.
"$bin/cloudgen" blender "$tmp/tiny.vdb" -q -o "$tmp/scene.blend" --render "$tmp/cycles.png" --size 128x72 --samples 8
test -s "$tmp/scene.blend" && test -s "$tmp/cycles.png"
# Nothing else is left beside them: no staged temporary, no Blender "NAME.blend1" backup of one.
left="$(find "$tmp" -maxdepth 1 -name '.*tmp*' -o -maxdepth 1 -name '*.blend1')"
if [ -n "$left" ]; then echo "left beside the outputs: $left"; exit 1; fi
blender_py check "$tmp/scene.blend" "$tmp/cycles_mask.png" "$voxel" ${bounds//,/ } "$tmp/full.vdb" 800

# 4. The viewer's default view of the same file (transmittance, no tone curve) against Cycles' mask;
#    the up = y file must give the viewer the same picture.
vset=(--set render.output=transmittance render.tonemap=clamp render.exposure=1 render.bloom=0)
"$bin/cloudviewer" "$tmp/tiny.vdb" --headless --size 128x72 "${vset[@]}" --out "$tmp/viewer_t.png" >/dev/null
"$bin/cloudviewer" "$tmp/tiny-y.vdb" --headless --size 128x72 "${vset[@]}" --out "$tmp/viewer_t_y.png" >/dev/null
"$bin/cloudviewer" "$tmp/tiny.vdb" --headless --size 128x72 --out "$tmp/viewer.png" >/dev/null
cmp "$tmp/viewer_t.png" "$tmp/viewer_t_y.png" && echo "viewer: the up = y file gives the same picture as up = z"
blender_py compare "$tmp/viewer_t.png" "$tmp/cycles_mask.png" "$tmp/viewer.png" "$tmp/cycles.png"
# The scene of the y-up file (its object turned upright in Blender) frames the same cloud.
"$bin/cloudgen" blender "$tmp/tiny-y.vdb" -q -o "$tmp/scene-y.blend" --size 128x72 --samples 8
blender_py mask "$tmp/scene-y.blend" "$tmp/cycles_mask_y.png" >/dev/null
blender_py compare "$tmp/viewer_t_y.png" "$tmp/cycles_mask_y.png" | grep -E "IoU|agree"
# 5. Cycles puts a one-voxel grid where OpenVDB's indexToWorld and the viewer do (Blender 3.4
#    renders half a voxel off, 9 px here; the scene shifts it back). A 3^3 box of 10 m voxels with
#    a dense middle voxel (and two faint corners that keep the box), without a view, so both
#    renderers also frame it the same bare way.
"$bin/cloudgen" generate tiny -q --set 'resolution=[3,3,3]' --set threshold=0 --set density_scale=1000 \
  --set 'origin=[100,200,300]' --set voxel_size=10 --set view.render.sigma_t=3 --set view.render.ground=false \
  --set export.vdb.detail=false -o "$tmp/box.vdb"
$py - "$tmp/box.vdb" "$tmp/voxel.vdb" <<'PY'
import sys, pyopenvdb as vdb
grids, meta = vdb.readAll(sys.argv[1])
g = grids[0]
one = vdb.FloatGrid(0.0)
one.name, one.transform, one.gridClass = "density", g.transform, g.gridClass
for k, v in g.metadata.items():
    if k != "view":  # no view: both renderers frame the bare box (30 degrees above, filling the frame)
        one[k] = v
acc = one.getAccessor()
for c in ((0, 0, 0), (2, 2, 2)):
    acc.setValueOn(c, 1e-6)
acc.setValueOn((1, 1, 1), 1.0)
vdb.write(sys.argv[2], grids=[one], metadata=meta)
PY
"$bin/cloudviewer" "$tmp/voxel.vdb" --headless --size 64x64 "${vset[@]}" --out "$tmp/voxel_viewer_t.png" >/dev/null
"$bin/cloudgen" blender "$tmp/voxel.vdb" -q -o "$tmp/voxel.blend" --size 64x64 --samples 8
blender_py mask "$tmp/voxel.blend" "$tmp/voxel_cycles_mask.png" >/dev/null
blender_py centroid "$tmp/voxel_viewer_t.png" "$tmp/voxel_cycles_mask.png" 1.5
# 6. Levels of detail (generate --lod): Blender lists the level grids on the volume object, and
#    `cloudgen blender --level 2` points Principled Volume's Density Attribute at density_level_2;
#    a level the file lacks is refused with the allowed range, exit 1, no scene written.
"$bin/cloudgen" generate tiny -q --lod 2 -o "$tmp/lod.vdb"
"$bin/cloudgen" blender "$tmp/lod.vdb" -q --level 2 -o "$tmp/lod.blend" --size 64x36 --samples 4
cat > "$tmp/lod_check.py" <<'PY'
import bpy
(vol,) = bpy.data.volumes
vol.grids.load()
names = [g.name for g in vol.grids]
assert {"density", "density_level_1", "density_level_2"} <= set(names), names
attrs = [n.inputs["Density Attribute"].default_value for m in bpy.data.materials for n in m.node_tree.nodes
         if n.type == "PRINCIPLED_VOLUME"]
assert attrs == ["density_level_2"], attrs
print("blender: grids", names, "; the material reads", attrs[0])
PY
blender -b "$tmp/lod.blend" --python-exit-code 1 --python "$tmp/lod_check.py" 2>&1 | grep -E "^blender: grids|Error|assert"
if "$bin/cloudgen" blender "$tmp/lod.vdb" -q --level 3 -o "$tmp/lod3.blend" 2>"$tmp/lod3.err"; then
  echo "--level 3 of a file with 2 levels was accepted"; exit 1
fi
grep -q -- "--level: 3 is not a level of detail of .*; allowed: 0 .. 2" "$tmp/lod3.err" || { cat "$tmp/lod3.err"; exit 1; }
test ! -e "$tmp/lod3.blend"
# 7. A mesh through `cloudgen shape` renders in Cycles as the mesh, not as its box: a standing torus
#    (written here) gives a ring whose hole, the image's centre, stays clear in Cycles' mask, and
#    whose mask agrees with the viewer's.
$py - "$tmp/torus.obj" <<'PY'
import math, sys
nu, nv, R, r, a = 48, 16, 2.0, 0.7, math.radians(70)
with open(sys.argv[1], "w") as f:
    for i in range(nu):
        for j in range(nv):
            u, v = 2 * math.pi * i / nu, 2 * math.pi * j / nv
            x, y, z = (R + r * math.cos(v)) * math.cos(u), r * math.sin(v), (R + r * math.cos(v)) * math.sin(u)
            f.write(f"v {x:.5f} {y * math.cos(a) - z * math.sin(a):.5f} {y * math.sin(a) + z * math.cos(a):.5f}\n")
    at = lambda i, j: (i % nu) * nv + (j % nv) + 1
    for i in range(nu):
        for j in range(nv):
            f.write(f"f {at(i, j)} {at(i, j + 1)} {at(i + 1, j + 1)} {at(i + 1, j)}\n")
PY
"$bin/cloudgen" shape "$tmp/torus.obj" -q -o "$tmp/torus.vdb" --size 1200 --voxel-size 30
"$bin/cloudviewer" "$tmp/torus.vdb" --headless --size 128x72 "${vset[@]}" --out "$tmp/torus_viewer_t.png" >/dev/null
"$bin/cloudgen" blender "$tmp/torus.vdb" -q -o "$tmp/torus.blend" --size 128x72 --samples 8
blender_py mask "$tmp/torus.blend" "$tmp/torus_mask.png" >/dev/null
blender_py compare "$tmp/torus_viewer_t.png" "$tmp/torus_mask.png" | grep -E "IoU|agree"
$py - "$tmp/torus_mask.png" <<'PY'
import sys, matplotlib.image as mpimg
a = mpimg.imread(sys.argv[1])[..., 3]
h, w = a.shape
hole, ring = a[h // 2 - 3:h // 2 + 4, w // 2 - 3:w // 2 + 4].max(), (a > 0.1).mean()
print(f"torus: Cycles alpha at most {hole:.3f} in the hole, cloud on {100 * ring:.1f}% of the frame")
assert hole <= 0.1 and ring > 0.05, (hole, ring)
PY
if [ -n "${CLOUD_KEEP_RENDER:-}" ]; then mkdir -p "$CLOUD_KEEP_RENDER" && cp "$tmp"/*.png "$CLOUD_KEEP_RENDER"/; fi
echo "blender round trip OK"
