#!/usr/bin/env bash
# CTest: a baked VDB sequence (`cloudgen generate --frames`) read by OpenVDB's Python binding
# (velocity grid, the frame box following the wind) and played by Blender as a volume sequence
# (`cloudgen blender c_####.vdb --frames A:B`), whose last frame Cycles renders where the viewer
# renders that frame's file. Usage: blender_sequence.sh BUILD_BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
py=/usr/bin/python3

# 1. A box preset blown along +x at 100 m/s, 1 fps, no flow and no shear: 4 voxels (100 m) per
#    frame, so frame 5 is frame 2 moved by exactly 300 m, and the velocity is (100, 0, 0). The
#    range starts after 0: a volume loaded before it is in the scene reads file 0, which is absent.
"$bin/cloudgen" generate tiny -q --set tiling=false --set motion.wind_speed=100 --set motion.wind_direction=90 \
  --set motion.wind_shear=0 --set motion.flow_speed=0 --frames 2:5 --fps 1 -o "$tmp/c_####.vdb"
$py - "$tmp" <<'PY'
import sys, pyopenvdb as vdb
d = sys.argv[1]
def load(f):
    grids, _ = vdb.readAll(f"{d}/c_{f:04d}.vdb")
    return {g.name: g for g in grids}
def world_values(g):
    out = {}
    for it in g.iterOnValues():
        lo, hi = it.min, it.max
        for i in range(lo[0], hi[0] + 1):
            for j in range(lo[1], hi[1] + 1):
                for k in range(lo[2], hi[2] + 1):
                    w = g.transform.indexToWorld((i, j, k))
                    out[tuple(round(c, 3) for c in w)] = it.value
    return out
g0, g3 = load(2), load(5)
assert g3["density"].metadata["frame"] == 5 and abs(g3["density"].metadata["time_seconds"] - 5.0) < 1e-12
d0, d3 = world_values(g0["density"]), world_values(g3["density"])
moved = {(x + 300.0, y, z): v for (x, y, z), v in d0.items()}
moved = {tuple(round(c, 3) for c in k): v for k, v in moved.items()}
# cos(90 deg) = 6e-17 leaves a 2e-14 m drift along z: voxels below 1e-6 may appear or vanish.
keys = {k for k, v in moved.items() if v > 1e-6} | {k for k, v in d3.items() if v > 1e-6}
worst = max(abs(moved.get(k, 0.0) - d3.get(k, 0.0)) for k in keys)
assert worst < 1e-6, f"frame 5 is not frame 2 moved 300 m along +x: a voxel differs by {worst}"
v3 = world_values(g3["velocity"])
assert set(v3) == set(d3), "velocity is not on the density's active voxels"
worst_v = max(max(abs(a - b) for a, b in zip(v, (100.0, 0.0, 0.0))) for v in v3.values())
assert worst_v < 1e-3, worst_v
print(f"openvdb: frame 5 = frame 2 moved 300 m along +x ({len(keys)} voxels, max diff {worst:.1e}); "
      f"velocity (100, 0, 0) m/s within {worst_v:.1e} on every density voxel")
PY

# A wind toward -z (azimuth 0): velocity (0, 0, -100) in a y-up file, turned like the positions
# to (0, 100, 0) in a z-up (Blender) file.
for up in y z; do
  "$bin/cloudgen" generate tiny -q --up $up --set motion.wind_speed=100 --set motion.wind_direction=0 \
    --set motion.wind_shear=0 --set motion.flow_speed=0 --frames 1 -o "$tmp/north_$up.vdb"
done
$py - "$tmp" <<'PY'
import sys, pyopenvdb as vdb
d = sys.argv[1]
for up, want in (("y", (0.0, 0.0, -100.0)), ("z", (0.0, 100.0, 0.0))):
    g = vdb.read(f"{d}/north_{up}.vdb", "velocity")
    assert g.activeVoxelCount() > 0
    worst = max(max(abs(a - b) for a, b in zip(it.value, want)) for it in g.iterOnValues())
    assert worst < 1e-3, (up, worst)
print("openvdb: a wind toward -z is (0, 0, -100) m/s in the y-up file and (0, 100, 0) in the z-up file")
PY

# Frame 0 of the default motion is the static export's density grid: same transform, active
# voxels and values; the metadata differs only by the sequence's own keys.
"$bin/cloudgen" generate tiny -q -o "$tmp/static.vdb"
"$bin/cloudgen" generate tiny -q --frames 0:1 -o "$tmp/zero_#.vdb"
$py - "$tmp/static.vdb" "$tmp/zero_0.vdb" <<'PY'
import sys, pyopenvdb as vdb
a, b = (vdb.read(p, "density") for p in sys.argv[1:3])
def voxels(g):
    out = {}
    for it in g.iterOnValues():
        lo, hi = it.min, it.max
        for i in range(lo[0], hi[0] + 1):
            for j in range(lo[1], hi[1] + 1):
                for k in range(lo[2], hi[2] + 1):
                    out[(i, j, k)] = it.value
    return out
assert a.transform.info() == b.transform.info(), (a.transform.info(), b.transform.info())
va, vb = voxels(a), voxels(b)
assert va == vb, f"{len(set(va) ^ set(vb))} voxels differ in place, or values differ"
extra = {k for k in set(a.metadata) ^ set(b.metadata) if not k.startswith("file_")}
seq = {"frame", "time_seconds", "fps", "frame_first", "frame_last"}
assert all(k in seq or k.startswith("motion.") for k in extra), extra
same = {k for k in set(a.metadata) & set(b.metadata) if not k.startswith("file_")}
assert all(a.metadata[k] == b.metadata[k] for k in same), [k for k in same if a.metadata[k] != b.metadata[k]]
print(f"openvdb: frame 0 holds the static density grid exactly ({len(va)} voxels), plus {len(extra)} sequence keys")
PY

# 2. Blender plays the files as a volume sequence; Cycles' last frame against the viewer's.
"$bin/cloudgen" blender "$tmp/c_####.vdb" --frames 2:5 -q -o "$tmp/seq.blend" --size 128x72 --samples 4
blender -b --factory-startup --python-exit-code 1 --python "$src/tests/blender_sequence.py" -- \
  "$tmp/seq.blend" 2 4 "$tmp" > "$tmp/blender.log" 2>&1 || { tail -20 "$tmp/blender.log"; exit 1; }
grep -E "^blender:" "$tmp/blender.log"
test -s "$tmp/mask_2.png" && test -s "$tmp/mask_5.png"
vset=(--set render.output=transmittance render.tonemap=clamp render.exposure=1 render.bloom=0)
for f in 2 5; do
  "$bin/cloudviewer" "$tmp/c_000$f.vdb" --headless --size 128x72 "${vset[@]}" --out "$tmp/viewer_$f.png" >/dev/null
done
cmp_masks() { blender -b --factory-startup --python-exit-code 1 --python "$src/tests/blender_roundtrip.py" -- \
  compare "$@" 2>&1 | grep -E "IoU|agree|SystemExit|Error" ; return "${PIPESTATUS[0]}"; }
cmp_masks "$tmp/viewer_5.png" "$tmp/mask_5.png"
cmp_masks "$tmp/viewer_2.png" "$tmp/mask_2.png"
# The played frame is the moving one: Cycles' frame 5 is not the viewer's frame 2.
if other="$(cmp_masks "$tmp/viewer_2.png" "$tmp/mask_5.png")"; then
  echo "Cycles' frame 5 matches the viewer's frame 2: the sequence did not advance ($other)"; exit 1
fi
echo "Cycles' frame 5 against the viewer's frame 2 (must differ): $(echo "$other" | grep -o 'IoU [0-9.]*' | head -1)"
if [ -n "${CLOUD_KEEP_RENDER:-}" ]; then mkdir -p "$CLOUD_KEEP_RENDER" && cp "$tmp"/*.png "$CLOUD_KEEP_RENDER"/; fi
echo "blender sequence OK"
