#!/usr/bin/env bash
# The real-time lighting against the path tracer in linear light (issue 42, docs/accuracy.md): the
# cloud's own radiance L - T * L_bg, per case mean ratio, relRMSE and darkest-quarter ratio, on four
# scenes x extinction x light x phase, sun only and with the sky light. Rewrites the table in
# docs/notes/accuracy.md and docs/images/accuracy_linear.png. About an hour on 2 cores.
# Usage: scripts/accuracy.sh [--spp N] [--size WxH] [--quick] [--work DIR] [--no-doc]
#   (after scripts/test.sh; needs Debian's blender to read the EXRs). The display-space studies:
#   scripts/accuracy_octaves.sh and scripts/accuracy_matrix.py.
set -euo pipefail
cd "$(dirname "$0")/.."
exec /usr/bin/python3 scripts/accuracy_linear.py "$@"
