#!/usr/bin/env bash
# CTest: cloudgen VDB -> independent check with OpenVDB's Python binding -> Blender import and a
# tiny Cycles render. Usage: blender_roundtrip.sh BUILD_BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
"$bin/cloudgen" generate tiny -q -o "$tmp/tiny.vdb"
# OpenVDB's own Python reader: grid class, value range, world bounding box (for Blender's check).
read -r bounds voxel < <(/usr/bin/python3 - "$tmp/tiny.vdb" <<'PY'
import sys, pyopenvdb as vdb
grids, meta = vdb.readAll(sys.argv[1])
g = {x.name: x for x in grids}["density"]
assert g.gridClass == vdb.GridClass.FOG_VOLUME, g.gridClass
assert g.background == 0.0
assert not str(meta.get("creator", "")).startswith("Houdini")
lo_v, hi_v = g.evalMinMax()
assert 0.0 <= lo_v and hi_v <= 1.0, (lo_v, hi_v)
# Blender's object bounds span the voxel centres of the union of all grids' active voxels.
los, his = zip(*(x.evalActiveVoxelBoundingBox() for x in grids))
i0, j0, k0 = (min(c[a] for c in los) for a in range(3))
i1, j1, k1 = (max(c[a] for c in his) for a in range(3))
xf = g.transform
lo = xf.indexToWorld((i0, j0, k0))
hi = xf.indexToWorld((i1, j1, k1))
print(",".join(f"{v:.6f}" for v in (*lo, *hi)), xf.voxelSize()[0])
PY
)
echo "openvdb: world bbox $bounds, voxel $voxel"
blender -b --factory-startup --python-exit-code 1 --python "$src/tests/blender_roundtrip.py" -- \
  "$tmp/tiny.vdb" "$tmp/render.png" ${bounds//,/ } "$voxel" 2>&1 | grep -vE "^(Fra:|Blender quit|Read blend|Saved)" | tail -20
test -s "$tmp/render.png"
[ -n "${CLOUD_KEEP_RENDER:-}" ] && cp "$tmp/render.png" "$CLOUD_KEEP_RENDER"
exit 0
