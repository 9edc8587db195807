#!/usr/bin/env bash
# CTest, issue 45 item 4: the window's direct handles, for real, under Xvfb (window_edit.sh's style).
# CLOUDVIEWER_WINDOW_ACTIONS drives them through the functions the GLFW callbacks call:
#  - a Shift + drag on the sky moves the sun: the picture changes, the window prints the new sun,
#    and Save preset as keeps it (the saved preset, opened fresh, draws the same frame byte for byte);
#  - the time of day (render.time_of_day, as the panel's slider sets it) puts the sun on the day's
#    path, kept the same way;
#  - Reset view after an orbit gives back the start frame byte for byte; a bookmark stored before
#    Reset view and recalled after it gives back the orbited frame.
# Usage: window_handles.sh BUILD_BIN_DIR SOURCE_DIR [PICTURE_DIR]  (PICTURE_DIR: keep the PNGs there)
set -euo pipefail
bin="$(cd "$1" && pwd)"; src="$(cd "$2" && pwd)"; keep="${3:-}"
if ! command -v xvfb-run >/dev/null; then
  echo "SKIP: xvfb-run is not installed (Debian package xvfb); the real-window test needs it"
  exit 77
fi
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
small=(--set 'resolution=[64,32,64]' --set voxel_size=50)
look=(--size 320x180 --set render.bloom=0)
view() {  # INPUT LOG OUT [ARGS...]: a window that saves its frame to OUT and closes
  local input="$1" log="$2" png="$3"; shift 3
  timeout 300 xvfb-run -a "$bin/cloudviewer" "$input" "${look[@]}" "$@" --out "$png" > "$log" 2>&1 ||
    { cat "$log"; exit 1; }
  if grep -q "CLOUDVIEWER_WINDOW_ACTIONS" "$log"; then cat "$log"; exit 1; fi
}
preset="$src/presets/cumulus.json"
view "$preset" "$tmp/plain.log" "$tmp/plain.png" "${small[@]}"

# The sun dragged from the upper left of the sky to the upper right, then saved.
mkdir "$tmp/drag"
(cd "$tmp/drag" && CLOUDVIEWER_WINDOW_ACTIONS="sundrag:0.2,0.15,0.8,0.1 save" \
   view "$preset" drag.log drag.png "${small[@]}")
sun="$(sed -n 's/^sun \([^ ]*\) (azimuth, elevation)$/\1/p' "$tmp/drag/drag.log" | tail -1)"
[ -n "$sun" ] || { echo "the drag moved no sun:"; cat "$tmp/drag/drag.log"; exit 1; }
grep -q "^saved cumulus_edited.json" "$tmp/drag/drag.log" || { echo "no save:"; cat "$tmp/drag/drag.log"; exit 1; }
"$bin/cloudgen" validate "$tmp/drag/cumulus_edited.json"
view "$tmp/drag/cumulus_edited.json" "$tmp/drag_saved.log" "$tmp/drag_saved.png"
cmp "$tmp/drag/drag.png" "$tmp/drag_saved.png" || { echo "the saved preset does not draw the dragged sun"; exit 1; }

# The time of day, as the panel's slider sets it: a summer evening at 45 N, then saved.
mkdir "$tmp/tod"
(cd "$tmp/tod" && CLOUDVIEWER_WINDOW_ACTIONS="set:time_of_day=19.25 save" view "$preset" tod.log tod.png "${small[@]}")
tod_sun="$(sed -n 's/^sun \([^ ]*\) (azimuth, elevation)$/\1/p' "$tmp/tod/tod.log" | tail -1)"
[ -n "$tod_sun" ] || { echo "the time of day moved no sun:"; cat "$tmp/tod/tod.log"; exit 1; }
view "$tmp/tod/cumulus_edited.json" "$tmp/tod_saved.log" "$tmp/tod_saved.png"
cmp "$tmp/tod/tod.png" "$tmp/tod_saved.png" || { echo "the saved preset does not draw the time of day's sun"; exit 1; }
# And it is the sun --set render.time_of_day gives a fresh window.
view "$preset" "$tmp/tod_set.log" "$tmp/tod_set.png" "${small[@]}" --set render.time_of_day=19.25
cmp "$tmp/tod/tod.png" "$tmp/tod_set.png" || { echo "the slider's sun differs from --set render.time_of_day"; exit 1; }

# Reset view after an orbit; a bookmark across a Reset view.
CLOUDVIEWER_WINDOW_ACTIONS="orbit:60,-25 reset" view "$preset" "$tmp/reset.log" "$tmp/reset.png" "${small[@]}"
grep -q "^view reset to the preset's view" "$tmp/reset.log" || { echo "no reset:"; cat "$tmp/reset.log"; exit 1; }
cmp "$tmp/plain.png" "$tmp/reset.png" || { echo "Reset view does not give back the preset's view"; exit 1; }
CLOUDVIEWER_WINDOW_ACTIONS="orbit:60,-25" view "$preset" "$tmp/orbit.log" "$tmp/orbit.png" "${small[@]}"
CLOUDVIEWER_WINDOW_ACTIONS="orbit:60,-25 store:3 reset recall:3" \
  view "$preset" "$tmp/bookmark.log" "$tmp/bookmark.png" "${small[@]}"
grep -q "^camera from bookmark 3" "$tmp/bookmark.log" || { echo "no recall:"; cat "$tmp/bookmark.log"; exit 1; }
cmp "$tmp/orbit.png" "$tmp/bookmark.png" || { echo "bookmark 3 does not give back the stored camera"; exit 1; }

/usr/bin/python3 - "$tmp" "$sun" "$tod_sun" <<'PY'
import json, sys
import numpy as np
from PIL import Image
d, sun, tod_sun = sys.argv[1], sys.argv[2], sys.argv[3]
load = lambda n: np.asarray(Image.open(f"{d}/{n}.png").convert("RGB")).astype(int)
plain = load("plain")
az, el = map(float, sun.split(","))
saved = json.load(open(f"{d}/drag/cumulus_edited.json"))["view"]["sun"]
assert (saved["azimuth"], saved["elevation"]) == (az, el), f"saved {saved}, the window printed {sun}"
assert (az, el) != (50, 30), "the drag left the preset's sun"
assert -10 <= el <= 90, f"elevation {el} out of the handles' range"
changed = {}
for name in ("drag/drag", "tod/tod", "orbit"):
    changed[name] = int((np.abs(load(name) - plain).max(axis=2) > 6).sum())
    assert changed[name] > 500, f"{name}: the picture hardly changed ({changed[name]} pixels)"
# The sun's disc is drawn where the drag let go: 0.8, 0.1 of the 320 x 180 window.
drag = load("drag/drag").sum(axis=2)
ys, xs = np.nonzero(drag >= drag.max() - 3)
cx, cy = xs.mean() + 0.5, ys.mean() + 0.5
assert len(xs) < 50 and abs(cx - 256) < 2 and abs(cy - 18) < 2, f"the sun's disc is at {cx:.1f},{cy:.1f}, not under the cursor"
taz, tel = map(float, tod_sun.split(","))
assert 270 < taz < 320 and -5 < tel < 15, f"19:15 on 21 June at 45 N: the sun low in the north-west, not {tod_sun}"
print(f"window handles: drag -> sun {az:.2f},{el:.2f} ({changed['drag/drag']} pixels changed, kept by Save as); "
      f"time of day 19.25 -> sun {taz:.2f},{tel:.2f} ({changed['tod/tod']} pixels); "
      f"the sun's disc at {cx:.1f},{cy:.1f} under the cursor (256,18); "
      "Reset view and bookmark 3 give back their frames byte for byte")
PY
if [ -n "$keep" ]; then
  mkdir -p "$keep"
  cp "$tmp/plain.png" "$keep/before.png"; cp "$tmp/drag/drag.png" "$keep/sun_drag.png"; cp "$tmp/tod/tod.png" "$keep/sunset.png"
  cp "$tmp/orbit.png" "$keep/orbit.png"; cp "$tmp/drag/drag.window.png" "$keep/sun_drag.window.png"
fi
