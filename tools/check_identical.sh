#!/usr/bin/env bash
# Shows that a change altered no physics: runs every scene in scenes/ for a short time in every
# 'method mode' pair it loads with (sph-run --list-modes), once with the sph-run of BEFORE (a
# commit, built in a worktree) and once with AFTER (a commit, or the working tree by default),
# and compares, byte for byte, every frame (all three formats, every attribute), every probe
# series, the physics columns of stats.csv and the physics keys of summary.json; plus one
# 1.2 s run of scenes/shock.json, whose PCISPH shock detection rolls steps back.
#
# usage: tools/check_identical.sh BEFORE [AFTER]     e.g. tools/check_identical.sh f460fa9
#   SPH_CHECK_END   simulated seconds per run (default 0.04)
#   SPH_CHECK_FPS   frame rate of the runs (default 100: 4-5 frames each)
# Both builds use 2 threads; the runs are deterministic at a fixed thread count. Exits 1 and
# lists the first differences when anything differs. Outputs stay in build-identical/.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
before=${1:?usage: tools/check_identical.sh BEFORE [AFTER]}
after=${2:-WORKTREE}
end=${SPH_CHECK_END:-0.04}
fps=${SPH_CHECK_FPS:-100}
work=$root/build-identical
mkdir -p "$work"

# Builds sph-run of a revision (or of the working tree) and prints its path.
build_rev() {
  local rev=$1 src bdir
  if [ "$rev" = WORKTREE ]; then
    src=$root; bdir=$work/build-worktree
  else
    local sha; sha=$(git rev-parse --short=12 "$rev^{commit}")
    src=$work/src-$sha; bdir=$work/build-$sha
    [ -d "$src" ] || git worktree add --detach "$src" "$sha" >/dev/null 2>&1
  fi
  cmake -S "$src" -B "$bdir" -DCMAKE_BUILD_TYPE=Release -DSPH_BUILD_TESTS=OFF -DSPH_BUILD_BENCH=OFF >/dev/null
  cmake --build "$bdir" --target sph-run -j"$(nproc)" >"$bdir.log" 2>&1 || { cat "$bdir.log" >&2; exit 1; }
  echo "$bdir/tools/sph-run"
}

# Runs every scene x mode with one sph-run into $2.
run_all() {
  local exe=$1 out=$2 scene name method mode
  rm -rf "$out"; mkdir -p "$out"
  for scene in scenes/*.json; do
    name=$(basename "$scene" .json)
    while read -r method mode; do
      [ -n "$method" ] || continue
      "$exe" "$scene" -q --threads 2 --end "$end" --out "$out/$name-$method-$mode" \
        --set simulation.method="$method" --set simulation.stepping.mode="$mode" \
        --set simulation.frame_rate="$fps" --set 'output.format=["vtu","bgeo","ply"]' \
        --set 'output.attributes=["position","velocity","density","pressure","acceleration","dt","active"]' \
        >"$out/$name-$method-$mode.log" 2>&1 || echo "exit $? (kept: the other side must fail alike)" >>"$out/$name-$method-$mode.log"
    done < <("$exe" "$scene" --list-modes -q)
  done
  # One longer run that rolls back (PCISPH shock detection discards steps 294 and 298 of
  # scenes/shock.json), so the rollback path is compared too.
  "$exe" scenes/shock.json -q --threads 2 --end 1.2 --set simulation.frame_rate=10 --out "$out/shock-rollback" \
    >"$out/shock-rollback.log" 2>&1 || echo "exit $?" >>"$out/shock-rollback.log"
}

# A commit's outputs are kept (out-<sha>/, marked complete by .done) and reused; the working
# tree's are always made anew.
outputs_of() {
  local rev=$1 exe out
  if [ "$rev" = WORKTREE ]; then out=$work/out-worktree; else out=$work/out-$(git rev-parse --short=12 "$rev^{commit}"); fi
  if [ "$rev" = WORKTREE ] || [ ! -f "$out/.done" ]; then
    exe=$(build_rev "$rev")
    echo "running every scene and mode with $rev ($exe)" >&2
    run_all "$exe" "$out"
    touch "$out/.done"
  fi
  echo "$out"
}
out_before=$(outputs_of "$before")
out_after=$(outputs_of "$after")
echo "before: $before ($out_before)"
echo "after:  $after ($out_after)"
python3 tools/compare_runs.py "$out_before" "$out_after"
