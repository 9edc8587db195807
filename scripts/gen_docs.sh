#!/usr/bin/env bash
# Regenerates docs/presets.md and docs/reference/viewer-params.md from their parameter tables
# (the test suite checks both are current), and the README's preset gallery.
set -euo pipefail
cd "$(dirname "$0")/.."
{
  cat docs/presets.head.md
  build/bin/cloudgen presets --markdown
} > docs/presets.md

# docs/reference/viewer-params.md: the render, atmosphere and motion parameter tables and the
# window's parameter keys, between their BEGIN/END markers (the test suite checks they are current).
replace_block() {  # FILE NAME CONTENT_FILE
  /usr/bin/python3 - "$1" "$2" "$3" <<'PY'
import sys
path, name, content = sys.argv[1], sys.argv[2], open(sys.argv[3]).read()
text = open(path).read()
begin = text.index("<!-- BEGIN " + name)
begin = text.index("\n", begin) + 1
end = text.index("<!-- END " + name)
text = text[:begin] + content + text[end:]
tmp = path + ".tmp"
with open(tmp, "w") as f:
    f.write(text)
import os
os.replace(tmp, path)
PY
}
tmp="$(mktemp)"
params=docs/reference/viewer-params.md
trap 'rm -f "$tmp"' EXIT
build/bin/cloudviewer --params-markdown > "$tmp"
replace_block "$params" render-params "$tmp"
build/bin/cloudviewer --atmosphere-markdown > "$tmp"
replace_block "$params" atmosphere-params "$tmp"
build/bin/cloudviewer --motion-markdown > "$tmp"
replace_block "$params" motion-params "$tmp"
build/bin/cloudviewer --keys-markdown > "$tmp"
replace_block "$params" render-keys "$tmp"

# README: one small picture per shipped preset, the viewer's headless default view of it (the
# preset's own `view` when it has one), so a newcomer sees what each preset makes before running
# anything. `--no-pictures` skips them (they take a minute on the CPU).
if [ "${1:-}" != "--no-pictures" ]; then
  mkdir -p docs/images
  for p in presets/*.json; do
    name="$(basename "$p" .json)"
    input="$p"
    # A preset too large to open densely (sky-100km: 6.4 G voxels) is shown at 1000 voxels along
    # its longest axis, through a VDB (the viewer opens presets densely).
    if [ "$(/usr/bin/python3 -c 'import json,sys; r=json.load(open(sys.argv[1]))["resolution"]; print(r[0]*r[1]*r[2] > 1<<28)' "$p")" = True ]; then
      input="$(mktemp -d)/$name.vdb"
      build/bin/cloudgen generate "$p" --resolution 1000 --mpi -q -o "$input"
    fi
    build/bin/cloudviewer "$input" --headless --size 240x135 --out "docs/images/preset_$name.png" >/dev/null
    if [ "$input" != "$p" ]; then rm -r "$(dirname "$input")"; fi
  done
  # Rows of five: a name row over a picture row (a markdown table needs one header row; the
  # first names are it, the later name rows are plain rows).
  : > "$tmp"
  presets=(presets/*.json)
  for ((i = 0; i < ${#presets[@]}; i += 5)); do
    names="" pics="" seps=""
    for p in "${presets[@]:i:5}"; do
      name="$(basename "$p" .json)"
      names+="| \`$name\` " pics+="| ![$name](docs/images/preset_$name.png) " seps+="|---"
    done
    if [ "$i" -eq 0 ]; then printf '%s|\n%s|\n' "$names" "$seps" >> "$tmp"; else printf '%s|\n' "$names" >> "$tmp"; fi
    printf '%s|\n' "$pics" >> "$tmp"
  done
  replace_block README.md preset-gallery "$tmp"
fi
