#!/usr/bin/env bash
# CTest, issue 42 item 3: the reference in the window, under Xvfb. The C key's toggle (driven as
# the CLOUDVIEWER_WINDOW_ACTIONS step "reference", the panel hidden) replaces the preview with the
# path tracer's progressive image; once it holds --spp paths per pixel the window shows what
# `cloudviewer --headless --backend pathtrace --spp N` writes for the same view, pixel for pixel
# (8-bit, at most 1 level apart: the passes' sums round in another order), and not the preview.
# Usage: window_reference.sh BUILD_BIN_DIR SOURCE_DIR
set -euo pipefail
bin="$(cd "$1" && pwd)"; src="$(cd "$2" && pwd)"
if ! command -v xvfb-run >/dev/null; then
  echo "SKIP: xvfb-run is not installed (Debian package xvfb); the real-window test needs it"
  exit 77
fi
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
args=("$src/presets/tiny.json" --size 160x90 --spp 8)
window() { timeout 300 xvfb-run -a "$bin/cloudviewer" "${args[@]}" "$@"; }
(cd "$tmp" && CLOUDVIEWER_WINDOW_ACTIONS="panel reference" window --out ref.png > ref.log 2>&1) || { cat "$tmp/ref.log"; exit 1; }
(cd "$tmp" && CLOUDVIEWER_WINDOW_ACTIONS="panel" window --out preview.png > preview.log 2>&1) || { cat "$tmp/preview.log"; exit 1; }
"$bin/cloudviewer" "${args[@]}" --headless --backend pathtrace --out "$tmp/truth.png" > "$tmp/truth.log" 2>&1 ||
  { cat "$tmp/truth.log"; exit 1; }
/usr/bin/python3 - "$tmp" <<'PY'
import sys
import numpy as np
from PIL import Image
d = sys.argv[1]
load = lambda n: np.asarray(Image.open(f"{d}/{n}.png").convert("RGB")).astype(int)
ref, preview, truth = load("ref.window"), load("preview.window"), load("truth")
assert ref.shape == truth.shape, (ref.shape, truth.shape)
gap = np.abs(ref - truth).max()
assert gap <= 1, f"the window's reference differs from the headless path tracer by {gap} levels"
shown = (np.abs(ref - preview).max(axis=2) > 8).sum()
assert shown > 500, f"the reference looks like the preview ({shown} pixels differ): was it shown?"
print(f"window reference at 8 paths per pixel: at most {gap} level from the headless path tracer; "
      f"{shown} pixels differ from the preview")
PY
