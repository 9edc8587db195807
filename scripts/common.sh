# Shared by run.sh and test.sh: install what is missing, configure and build into build/.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

# ccache makes rebuilds from another clone of the same sources cheap (CI runs on the developer's
# machine): paths are hashed relative to the clone. install_missing turns it on once it is installed.
use_ccache() {
  command -v ccache >/dev/null 2>&1 || return 0
  export CMAKE_C_COMPILER_LAUNCHER=ccache CMAKE_CXX_COMPILER_LAUNCHER=ccache CCACHE_BASEDIR="$ROOT"
  # ccache 4.7 hashes the -fsanitize-ignorelist= path, not the file: hash its contents instead, so
  # an edit to it recompiles the sanitizer builds, and another clone's path still finds the objects.
  export CCACHE_EXTRAFILES="$ROOT/tests/fuzz/ubsan_ignore.txt" CCACHE_IGNOREOPTIONS="-fsanitize-ignorelist=*"
}

log() { printf '\033[1m==> %s\033[0m\n' "$*" >&2; }

# Installs the packages of the given lists that dpkg does not report as installed. A second run
# finds nothing missing and costs a fraction of a second.
install_missing() {
  local want=() missing=()
  for list in "$@"; do
    while read -r pkg; do
      pkg="${pkg%%#*}"; pkg="${pkg// /}"
      [ -n "$pkg" ] && want+=("$pkg")
    done < "$list"
  done
  for pkg in "${want[@]}"; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    log "all ${#want[@]} Debian packages present"
    use_ccache
    return
  fi
  log "installing missing Debian packages: ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  use_ccache
}

configure_and_build() {
  local jobs
  jobs="$(nproc)"
  log "configuring build/ (Release)"
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
  log "building with $jobs jobs"
  cmake --build build -j "$jobs"
}
