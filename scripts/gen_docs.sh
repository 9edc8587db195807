#!/usr/bin/env bash
# Regenerates docs/presets.md and the generated parts of docs/viewer.md from their parameter tables
# (the test suite checks both are current).
set -euo pipefail
cd "$(dirname "$0")/.."
{
  cat docs/presets.head.md
  build/bin/cloudgen presets --markdown
} > docs/presets.md

# docs/viewer.md: the render parameter table and the window's parameter keys, between their
# BEGIN/END markers (the test suite checks they are current).
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
trap 'rm -f "$tmp"' EXIT
build/bin/cloudviewer --params-markdown > "$tmp"
replace_block docs/viewer.md render-params "$tmp"
build/bin/cloudviewer --atmosphere-markdown > "$tmp"
replace_block docs/viewer.md atmosphere-params "$tmp"
build/bin/cloudviewer --keys-markdown > "$tmp"
replace_block docs/viewer.md render-keys "$tmp"
