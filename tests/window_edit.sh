#!/usr/bin/env bash
# CTest, issue 45 item 5: the window, for real, under Xvfb. A preset opened in a window gets an edit
# through the panel's own edit path (cloudviewer --edit in a window with --out: Session::edit_preset
# after the first frame, regenerated on the window's worker thread, then the frame is written). The
# window's frame must equal a fresh window's --set of the same key byte for byte (frame and panel
# screenshot), and differ from the unedited one only where the unedited cloud is: raising the
# threshold only removes cloud, so every pixel that changes by more than a few levels lies where the
# unedited transmittance is below 1 (the ground and bloom off, so no shadow or glow moves).
# Then the panel's file actions in the window (CLOUDVIEWER_WINDOW_ACTIONS presses the buttons):
# Save preset as writes a preset that validates and generates the edited volume's bytes, Export
# writes the bytes `cloudgen generate --set` writes, Open in Blender writes the .blend (with blender).
# Usage: window_edit.sh BUILD_BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$(cd "$1" && pwd)"; src="$(cd "$2" && pwd)"
if ! command -v xvfb-run >/dev/null; then
  echo "SKIP: xvfb-run is not installed (Debian package xvfb); the real-window test needs it"
  exit 77
fi
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
small=(--set 'resolution=[64,32,64]' --set voxel_size=50)
view() { timeout 300 xvfb-run -a "$bin/cloudviewer" "$src/presets/cumulus.json" --size 320x200 \
           "${small[@]}" --set render.ground=false --set render.bloom=0 "$@"; }
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

# The file actions, pressed in the window after the edit (from a folder of the test's own).
mkdir "$tmp/act"
actions="save export"
if command -v blender >/dev/null; then actions="$actions blender"; fi
(cd "$tmp/act" && CLOUDVIEWER_WINDOW_ACTIONS="$actions" view --edit threshold=0.6 --out act.png > act.log 2>&1) ||
  { cat "$tmp/act/act.log"; exit 1; }
grep -q "^saved cumulus_edited.json" "$tmp/act/act.log" || { echo "no save:"; cat "$tmp/act/act.log"; exit 1; }
"$bin/cloudgen" validate "$tmp/act/cumulus_edited.json"
"$bin/cloudgen" generate "$src/presets/cumulus.json" "${small[@]}" --set threshold=0.6 -q -o "$tmp/ref.vdb"
"$bin/cloudgen" generate "$tmp/act/cumulus_edited.json" -q -o "$tmp/saved.vdb"
cmp "$tmp/ref.vdb" "$tmp/act/cumulus_edited.vdb" || { echo "the window's Export differs from cloudgen generate --set"; exit 1; }
cmp "$tmp/ref.vdb" "$tmp/saved.vdb" || { echo "the saved preset generates another volume"; exit 1; }
if [[ "$actions" == *blender* ]]; then
  grep -q "^Blender scene cumulus_edited.blend" "$tmp/act/act.log" || { echo "no Blender scene:"; cat "$tmp/act/act.log"; exit 1; }
  test -s "$tmp/act/cumulus_edited.blend"
fi
echo "window file actions ($actions): the saved preset and the export make the edited volume's bytes"
