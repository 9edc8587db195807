#!/usr/bin/env bash
# Scale-out: MPI ranks and farm tiles write the one-process VDB (compared through OpenVDB by
# tests/vdb_equal.py: same grids, transforms, metadata, active voxels and values), missing or
# damaged tiles are named and --resume regenerates exactly those, `cloudgen tile --index` runs a
# plan's tiles as an indexed job would, and a rank that dies leaves no output. Usage: scale_out.sh BIN_DIR SOURCE_DIR [mpi|tiles]
set -uo pipefail
bin="$1"; src="$2"; part="${3:-all}"
cg="$bin/cloudgen"
eq="/usr/bin/python3 $src/tests/vdb_equal.py"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
fails=0
ok()   { echo "ok: $*"; }
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
# Three small presets: tiny (detail everywhere, 8 bricks), a sparse field where the bound skips
# bricks (128 bricks, some skipped, some detail-only), and cumulus, whose three detail channels
# the default export bakes into the density (the ranks and tiles bake brick by brick).
presets=("tiny" "cumulus-field --resolution 128" "cumulus --resolution 48")

# OpenMPI refuses root unless told; tests run as root in CI, so allow it here, for this run only.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1   # -n 3 on 2 cores

for i in "${!presets[@]}"; do
  # shellcheck disable=SC2086
  $cg generate ${presets[$i]} -q -o "$tmp/ref$i.vdb" || fail "one-process generate ${presets[$i]}"
done

if [[ "$part" == all || "$part" == mpi ]]; then
  # --mpi outside mpirun runs as a one-rank job (OpenMPI singleton).
  if $cg generate tiny --mpi -q --stats -o "$tmp/single.vdb" 2> "$tmp/log" && grep -q "on 1 ranks" "$tmp/log" &&
     $eq "$tmp/ref0.vdb" "$tmp/single.vdb"; then ok "--mpi without mpirun is one rank and equal"
  else fail "--mpi without mpirun: $(cat "$tmp/log")"; fi
  if ! command -v mpirun >/dev/null; then
    fail "mpirun not found (Debian package openmpi-bin)"
  else
    for i in "${!presets[@]}"; do
      for n in 2 3; do
        out="$tmp/mpi${n}_$i.vdb"
        # shellcheck disable=SC2086
        if mpirun -n $n --oversubscribe $cg generate ${presets[$i]} -q --stats -o "$out" 2> "$tmp/log"; then
          grep -q "on $n ranks" "$tmp/log" || fail "--stats does not say '$n ranks': $(cat "$tmp/log")"
          [[ $(grep -c "^  rank [0-9]*: " "$tmp/log") == "$n" ]] || fail "--stats has no line per rank"
          if $eq "$tmp/ref$i.vdb" "$out"; then ok "mpirun -n $n ${presets[$i]} equals the one-process VDB"
          else fail "mpirun -n $n ${presets[$i]} differs"; fi
        else
          fail "mpirun -n $n ${presets[$i]}: $(cat "$tmp/log")"
        fi
      done
    done
    # More ranks than bricks (tiny has 8): the idle ranks generate nothing, the output is the same.
    if mpirun -n 9 --oversubscribe $cg generate tiny -q --stats -o "$tmp/mpi9.vdb" 2> "$tmp/log" &&
       grep -q "8 bricks on 9 ranks" "$tmp/log" && $eq "$tmp/ref0.vdb" "$tmp/mpi9.vdb"; then
      ok "mpirun -n 9 (more ranks than bricks) equals the one-process VDB"
    else fail "mpirun -n 9: $(cat "$tmp/log")"; fi
    # A rank that dies (deterministically: rank 1 kills itself before sending its bricks) fails the
    # run, and rank 0 writes nothing, not even a temporary file.
    mkdir -p "$tmp/kill"
    if CLOUDGEN_TEST_KILL_RANK=1 mpirun -n 2 --oversubscribe $cg generate tiny -q -o "$tmp/kill/out.vdb" 2> "$tmp/log"; then
      fail "a killed rank did not fail the run"
    elif [[ -n "$(ls -A "$tmp/kill")" ]]; then
      fail "a killed rank left files: $(ls -A "$tmp/kill")"
    elif ! grep -q "rank 1" "$tmp/log"; then
      fail "the failure does not name rank 1: $(cat "$tmp/log")"
    else
      ok "a killed rank fails the run with no output"
    fi
  fi
fi

if [[ "$part" == nompi ]]; then
  # A build without MPI still generates, and says what is missing when asked for MPI.
  if $cg generate tiny --mpi -q -o "$tmp/x.vdb" 2> "$tmp/log"; then fail "--mpi succeeded in a build without MPI"
  elif ! grep -q "built without MPI" "$tmp/log" || [[ -e "$tmp/x.vdb" ]]; then fail "--mpi without MPI: $(cat "$tmp/log")"
  else ok "a build without MPI says so for --mpi"; fi
fi

if [[ "$part" == all || "$part" == tiles ]]; then
  i=1; t="$tmp/tiles"
  # shellcheck disable=SC2086
  $cg plan ${presets[$i]} --tiles 3,1,2 -o "$t/plan.json" 2> "$tmp/log" || fail "plan: $(cat "$tmp/log")"
  mapfile -t cmds < <(/usr/bin/python3 -c 'import json,sys; [print(t["command"]) for t in json.load(open(sys.argv[1]))["tiles"]]' "$t/plan.json")
  [[ ${#cmds[@]} == 6 ]] || fail "plan --tiles 3,1,2 has ${#cmds[@]} tiles, not 6"
  for c in "${cmds[@]}"; do
    [[ "$c" == "cloudgen generate "* ]] || fail "tile command is not a cloudgen generate: $c"
    (PATH="$bin:$PATH"; eval "$c") || fail "tile command failed: $c"
  done
  if $cg merge "$t/plan.json" -o "$tmp/merged.vdb" -q && $eq "$tmp/ref$i.vdb" "$tmp/merged.vdb"; then
    ok "plan + 6 tiles + merge equals the one-process VDB"
  else
    fail "plan + tiles + merge differs from the one-process VDB"
  fi
  # A missing tile: merge fails naming it and writes nothing.
  rm "$t/tile_0002.vdb"
  if $cg merge "$t/plan.json" -o "$tmp/m2.vdb" 2> "$tmp/log"; then fail "merge succeeded with a missing tile"
  elif [[ -e "$tmp/m2.vdb" ]]; then fail "merge with a missing tile left an output"
  elif ! grep -q "tile_0002.vdb): missing" "$tmp/log"; then fail "merge does not name the missing tile: $(cat "$tmp/log")"
  else ok "a deleted tile makes merge fail naming it"; fi
  # --resume regenerates exactly that tile (the others keep their files), and the result is right.
  touch -d @0 "$t"/tile_000[013-5].vdb  # the epoch as mtime: any rewrite shows, no sleeping needed
  others() { for f in "$t"/tile_000[013-5].vdb; do stat -c '%n %Y %s' "$f"; done; }
  others > "$tmp/before"
  if $cg merge "$t/plan.json" -o "$tmp/m3.vdb" --resume 2> "$tmp/log" && $eq "$tmp/ref$i.vdb" "$tmp/m3.vdb"; then
    regen=$(grep -c "^regenerating " "$tmp/log")
    others > "$tmp/after"
    changed=$(diff "$tmp/before" "$tmp/after" | grep -c '^>')
    if [[ $regen == 1 ]] && grep -q "^regenerating tile 2 " "$tmp/log" && [[ $changed == 0 ]] && [[ -e "$t/tile_0002.vdb" ]]; then
      ok "--resume regenerates exactly the deleted tile"
    else
      fail "--resume regenerated $regen tile(s), rewrote $changed others: $(cat "$tmp/log")"
    fi
  else
    fail "merge --resume: $(cat "$tmp/log")"
  fi
  # A damaged tile (truncated): named by its checksum in the plan; --resume repairs it.
  truncate -s 3000 "$t/tile_0004.vdb"
  if $cg merge "$t/plan.json" -o "$tmp/m4.vdb" 2> "$tmp/log"; then fail "merge accepted a truncated tile"
  elif ! grep -q "tile_0004.vdb): damaged" "$tmp/log" || [[ -e "$tmp/m4.vdb" ]]; then fail "truncated tile: $(cat "$tmp/log")"
  elif $cg merge "$t/plan.json" -o "$tmp/m4.vdb" --resume -q && $eq "$tmp/ref$i.vdb" "$tmp/m4.vdb"; then
    ok "a damaged tile is named, and --resume repairs it"
  else fail "--resume did not repair a truncated tile"; fi
  # Without recorded checksums (a fresh plan), a truncated tile is still caught while reading.
  /usr/bin/python3 - "$t/plan.json" <<'PY'
import json, sys
p = json.load(open(sys.argv[1]))
for t in p["tiles"]: t.pop("checksum", None)
json.dump(p, open(sys.argv[1], "w"))
PY
  truncate -s 3000 "$t/tile_0001.vdb"
  if $cg merge "$t/plan.json" -o "$tmp/m5.vdb" 2> "$tmp/log"; then fail "merge accepted a truncated tile without checksums"
  elif ! grep -q "tile_0001.vdb" "$tmp/log" || [[ -e "$tmp/m5.vdb" ]]; then fail "unchecksummed truncated tile: $(cat "$tmp/log")"
  else ok "a truncated tile without a checksum is named too"; fi
  # A tile of another seed is inconsistent.
  (PATH="$bin:$PATH"; eval "${cmds[0]} --seed 77") || fail "seed-77 tile"
  if $cg merge "$t/plan.json" -o "$tmp/m6.vdb" --resume 2> "$tmp/log" | true; grep -q "tile 0 .*inconsistent: preset_hash" "$tmp/log"; then
    ok "a tile of another seed is found inconsistent (and regenerated with --resume)"
  else fail "seed mismatch not reported: $(cat "$tmp/log")"; fi
  # `cloudgen tile PLAN --index I` (the indexed-job form) for every I, the last one through
  # JOB_COMPLETION_INDEX as a Kubernetes Indexed Job sets it, then merge: the one-process VDB.
  i=1; t="$tmp/indexed"
  # shellcheck disable=SC2086
  $cg plan ${presets[$i]} --tiles 3,1,2 -o "$t/plan.json" 2> "$tmp/log" || fail "plan: $(cat "$tmp/log")"
  for k in 0 1 2 3 4; do $cg tile "$t/plan.json" --index $k -q || fail "tile --index $k"; done
  JOB_COMPLETION_INDEX=5 $cg tile "$t/plan.json" 2> "$tmp/log" || fail "tile with JOB_COMPLETION_INDEX=5: $(cat "$tmp/log")"
  grep -q "tile_0005.vdb (tile 5 of 6" "$tmp/log" || fail "tile does not say which tile it wrote: $(cat "$tmp/log")"
  if $cg merge "$t/plan.json" -o "$tmp/indexed.vdb" -q && $eq "$tmp/ref$i.vdb" "$tmp/indexed.vdb"; then
    ok "plan + tile --index 0..5 + merge equals the one-process VDB"
  else fail "tile --index + merge differs from the one-process VDB"; fi
  # The same bytes as the tile's own command (the tile checksums merge recorded in the plan).
  if /usr/bin/python3 - "$t/plan.json" "$tmp/tiles/plan.json" <<'PY'
import json, sys
a, b = (json.load(open(f))["tiles"] for f in sys.argv[1:3])
sys.exit(0 if [x["checksum"] for x in a] == [x["checksum"] for x in b] else 1)
PY
  then ok "tile --index writes the bytes of the tile's command"; else fail "tile --index bytes differ from the command's"; fi
  # Bad index, no index, a plan from another version: exit 1, the reason, no tile written.
  rm -f "$t"/tile_*.vdb
  bad_tile() {  # WHAT EXPECTED_TEXT ARGS...
    local what="$1" want="$2"; shift 2
    "$@" 2> "$tmp/log"; local code=$?
    if [[ $code != 1 ]]; then fail "$what: exit $code, not 1: $(cat "$tmp/log")"
    elif ! grep -qF -- "$want" "$tmp/log"; then fail "$what: no \"$want\" in: $(cat "$tmp/log")"
    elif compgen -G "$t/tile_*" > /dev/null; then fail "$what: wrote $(ls "$t")"
    else ok "$what: exit 1, nothing written"; fi
  }
  bad_tile "tile --index 6 of 6" '--index: "6" is out of range; allowed: integer in [0, 5]' $cg tile "$t/plan.json" --index 6
  bad_tile "tile --index -1" '"-1" is out of range' $cg tile "$t/plan.json" --index -1
  bad_tile "JOB_COMPLETION_INDEX=x" 'JOB_COMPLETION_INDEX: "x" is out of range' env JOB_COMPLETION_INDEX=x $cg tile "$t/plan.json"
  bad_tile "tile without an index" 'set JOB_COMPLETION_INDEX' env -u JOB_COMPLETION_INDEX $cg tile "$t/plan.json"
  /usr/bin/python3 - "$t/plan.json" "$t/old.json" <<'PY'
import json, sys
p = json.load(open(sys.argv[1]))
p["generator"] = "cloudgen 0.0.1"
json.dump(p, open(sys.argv[2], "w"))
PY
  bad_tile "a plan from another version" 'made by cloudgen 0.0.1' $cg tile "$t/old.json" --index 0
  # Baked tiles (cumulus: the default export bakes its erosion into each tile's density) merge to
  # the one-process VDB too.
  i=2; t="$tmp/baked"
  # shellcheck disable=SC2086
  $cg plan ${presets[$i]} --tiles 2,2,1 -o "$t/plan.json" 2> "$tmp/log" || fail "plan: $(cat "$tmp/log")"
  mapfile -t cmds < <(/usr/bin/python3 -c 'import json,sys; [print(t["command"]) for t in json.load(open(sys.argv[1]))["tiles"]]' "$t/plan.json")
  for c in "${cmds[@]}"; do (PATH="$bin:$PATH"; eval "$c") || fail "tile command failed: $c"; done
  if $cg merge "$t/plan.json" -o "$tmp/baked.vdb" -q && $eq "$tmp/ref$i.vdb" "$tmp/baked.vdb"; then
    ok "plan + 4 baked tiles + merge equals the one-process VDB"
  else fail "baked tiles + merge differ from the one-process VDB"; fi
fi

echo "$fails failure(s)"
[[ $fails == 0 ]]
