#!/usr/bin/env bash
# CTest, issue 45 item 5: the window, for real, under Xvfb. A preset opened in a window gets an edit
# through the panel's own edit path (cloudviewer --edit in a window with --out: Session::edit_preset
# after the first frame, regenerated on the window's worker thread, then the frame is written). The
# window's frame must equal a fresh window's --set of the same key byte for byte (frame and panel
# screenshot), and differ from the unedited one only where the unedited cloud is: raising the
# threshold only removes cloud, so every pixel that changes by more than a few levels lies where the
# unedited transmittance is below 1 (the ground and bloom off, so no shadow or glow moves).
# Usage: window_edit.sh BUILD_BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$1"; src="$2"
if ! command -v xvfb-run >/dev/null; then
  echo "SKIP: xvfb-run is not installed (Debian package xvfb); the real-window test needs it"
  exit 77
fi
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
view() { timeout 300 xvfb-run -a "$bin/cloudviewer" "$src/presets/cumulus.json" --size 320x200 \
           --set 'resolution=[64,32,64]' --set voxel_size=50 --set render.ground=false --set render.bloom=0 "$@"; }
view --out "$tmp/plain.png" > "$tmp/plain.log" 2>&1 || { cat "$tmp/plain.log"; exit 1; }
view --set render.output=transmittance --out "$tmp/t.png" > "$tmp/t.log" 2>&1 || { cat "$tmp/t.log"; exit 1; }
view --edit threshold=0.6 --out "$tmp/edit.png" > "$tmp/edit.log" 2>&1 || { cat "$tmp/edit.log"; exit 1; }
view --set threshold=0.6 --out "$tmp/set.png" > "$tmp/set.log" 2>&1 || { cat "$tmp/set.log"; exit 1; }
grep -q "reloaded .*cumulus.json in" "$tmp/edit.log" || { echo "the edit did not regenerate:"; cat "$tmp/edit.log"; exit 1; }
cmp "$tmp/edit.png" "$tmp/set.png" || { echo "the window's edit differs from a fresh --set"; exit 1; }
cmp "$tmp/edit.window.png" "$tmp/set.window.png" || { echo "the window (panel included) differs from a fresh --set"; exit 1; }
/usr/bin/python3 - "$tmp" <<'PY'
import sys
import numpy as np
from PIL import Image
d = sys.argv[1]
load = lambda n: np.asarray(Image.open(f"{d}/{n}.png").convert("RGB")).astype(int)
plain, edit, t = load("plain"), load("edit"), load("t")
background = np.bincount(t[..., 0].ravel()).argmax()  # transmittance 1, the most common value
cloud = (t != background).any(axis=2)
diff = np.abs(plain - edit).max(axis=2)
big = diff > 6
assert big.sum() > 200, f"the edit hardly changed the picture ({big.sum()} pixels)"
outside = big & ~cloud
assert outside.sum() == 0, f"{outside.sum()} pixels changed where there was no cloud"
print(f"window edit: {big.sum()} pixels changed, all where the cloud was ({cloud.sum()} cloud pixels); "
      f"the edited window equals a fresh --set byte for byte")
PY
