#!/usr/bin/env bash
# CTest, issue 43 item 6: the density's 3D power spectrum is a falling power law over both bands
# (32-8 and 8-3 voxels: a log-log fit with R^2 >= 0.95 and a slope of -2 or steeper), not a flat
# floor, for the shaped species (scripts/realism.py --check); and the check can fail: a volume of
# white noise (a flat spectrum) is refused.
# Usage: realism_power_law.sh BUILD_BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$(cd "$1" && pwd)"; src="$(cd "$2" && pwd)"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
py=/usr/bin/python3
for p in cumulus-congestus cumulus-humilis; do
  "$bin/cloudgen" generate "$src/presets/$p.json" --up y -q -o "$tmp/$p.vdb"
done
"$py" "$src/scripts/realism.py" --check "$tmp/cumulus-congestus.vdb" "$tmp/cumulus-humilis.vdb"
"$py" - "$tmp/noise.vdb" <<'PY'
import sys
import numpy as np
import pyopenvdb as vdb
g = vdb.FloatGrid()
g.name = "density"
g.copyFromArray(np.random.default_rng(1).random((64, 64, 64), dtype=np.float32))
vdb.write(sys.argv[1], grids=[g])
PY
if "$py" "$src/scripts/realism.py" --check "$tmp/noise.vdb"; then
  echo "white noise passed the power-law check: the check cannot fail"
  exit 1
fi
echo "both species are falling power laws over both bands; white noise is refused"
