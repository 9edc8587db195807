#!/usr/bin/env bash
# Packs what scripts/device_check.sh runs on a lent GPU machine (an Ubuntu box without our Debian
# libraries and without a network): the Release cloudviewer, cloudgen and bench_temporal from build/
# with every shared library they load except glibc's, the C++ runtime's (the machine's are newer)
# and OpenGL's (glvnd there dispatches to the NVIDIA driver). Output: .device/bundle.tar.xz, in a
# folder git ignores through .git/info/exclude; name `.device` in the device run's `carry`.
# Usage: bash scripts/device_bundle.sh   (after scripts/run.sh or a build with -DCLOUD_BUILD_BENCH=ON)
source "$(dirname "$0")/common.sh"
bins=(build/bin/cloudviewer build/bin/cloudgen build/bin/bench_temporal)
for b in "${bins[@]}"; do
  [[ -x $b ]] || { echo "device_bundle: $b is missing: build with -DCLOUD_BUILD_BENCH=ON first" >&2; exit 1; }
done
grep -qx '/.device/' .git/info/exclude 2>/dev/null || echo '/.device/' >> .git/info/exclude
stage="$(mktemp -d)"
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/bin" "$stage/lib" .device
cp "${bins[@]}" "$stage/bin/"
# Libraries the system of any x86-64 Linux has (and must be its own): the C and C++ runtimes, the
# loader, and the GL dispatch libraries.
skip='^(ld-linux.*|libc|libm|libdl|libpthread|librt|libgcc_s|libstdc\+\+|libEGL|libGL|libGLX|libGLdispatch|libOpenGL|libGLES.*)\.so'
ldd "${bins[@]}" | awk '/=> \//{print $3}' | sort -u | while read -r lib; do
  name="$(basename "$lib")"
  [[ $name =~ $skip ]] && continue
  cp -L "$lib" "$stage/lib/$name"
done
tmp=".device/bundle.tar.xz.tmp.$$"
tar -C "$stage" -cJf "$tmp" bin lib
mv -f "$tmp" .device/bundle.tar.xz
log "wrote .device/bundle.tar.xz ($(du -h .device/bundle.tar.xz | cut -f1): ${#bins[@]} programs, $(ls "$stage/lib" | wc -l) libraries)"
