#!/usr/bin/env bash
# Regenerates docs/presets.md from the parameter table (the test suite checks it is current).
set -euo pipefail
cd "$(dirname "$0")/.."
{
  cat docs/presets.head.md
  build/bin/cloudgen presets --markdown
} > docs/presets.md
