#!/usr/bin/env bash
# sph-run end to end. Each check prints what it expected when it fails.
set -uo pipefail
run=$1; src=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
check() { if ! eval "$2"; then echo "FAIL: $1"; fail=1; else echo "ok: $1"; fi; }

# 1. A malformed scene: exit 2, the message names file, path, value, suggestion; no outputs.
bad=$src/tests/data/malformed/unknown_key_fluid_block.json
"$run" "$bad" --out "$tmp/bad" 2>"$tmp/err1"; rc=$?
check "malformed scene exits 2 (got $rc)" '[ $rc -eq 2 ]'
check "message names file, path and suggestion" 'grep -q "unknown_key_fluid_block.json: /fluid_blocks/0: found unknown key \"velocty\".*did you mean \"velocity\"" "$tmp/err1"'
check "no output directory after bad input" '[ ! -e "$tmp/bad" ]'

# 2. A bad command-line value is reported as set on the command line.
"$run" "$src/scenes/dam_break.json" --mode globel --out "$tmp/bad2" 2>"$tmp/err2"; rc=$?
check "unknown mode exits 2 (got $rc)" '[ $rc -eq 2 ]'
check "unknown mode suggests global" 'grep -q "did you mean \"global\"?) (set on the command line)" "$tmp/err2"'
"$run" "$src/scenes/dam_break.json" --mode adaptive --out "$tmp/bad4" 2>"$tmp/err4"; rc=$?
check "adaptive with wcsph exits 2 naming the method (got $rc)" '[ $rc -eq 2 ] && grep -q "for method \"wcsph\" (\"adaptive\" is the PCISPH mode" "$tmp/err4"'
"$run" "$src/scenes/shock.json" --mode global --out "$tmp/bad5" 2>"$tmp/err5"; rc=$?
check "global with pcisph exits 2 naming the method (got $rc)" '[ $rc -eq 2 ] && grep -q "expected one of \"constant\", \"adaptive\" for method \"pcisph\"" "$tmp/err5"'
"$run" "$tmp/does_not_exist.json" 2>"$tmp/err3"; rc=$?
check "missing file exits 2 (got $rc)" '[ $rc -eq 2 ] && grep -q "cannot open scene file" "$tmp/err3"'

# 3. A short good run writes stats.csv, summary.json, frames and the graph.
"$run" "$src/scenes/dam_break.json" --end 0.05 --out "$tmp/good" --graph "$tmp/g.dot" -q; rc=$?
check "short run exits 0 (got $rc)" '[ $rc -eq 0 ]'
check "summary.json reaches t = 0.05" 'python3 -c "import json,sys; s=json.load(open(\"$tmp/good/summary.json\")); sys.exit(0 if abs(s[\"simulated_time_s\"]-0.05)<1e-9 and s[\"steps\"]>10 and s[\"fluid_particles\"]==8000 else 1)"'
check "stats.csv has one row per step" 'python3 -c "import json,sys; s=json.load(open(\"$tmp/good/summary.json\")); n=len(open(\"$tmp/good/stats.csv\").read().splitlines())-1; sys.exit(0 if n==s[\"steps\"] else 1)"'
check "frames at 30 fps: t = 0 and one more" '[ -f "$tmp/good/frames/frame_00000.vtu" ] && [ -f "$tmp/good/frames/frame_00001.vtu" ]'
check "graph has the WCSPH nodes" 'grep -q "forces" "$tmp/g.dot" && grep -q -- "->" "$tmp/g.dot"'
check "no temporary files left" '[ -z "$(find "$tmp/good" -name "*.tmp*")" ]'

# 4. A particle leaving the domain: exit 3 naming the particle, the step and the system.
"$run" "$src/tests/data/valid/falls_out.json" --out "$tmp/fall" 2>"$tmp/err4"; rc=$?
check "leaving the domain exits 3 (got $rc)" '[ $rc -eq 3 ]'
check "diagnosis names particle, step and system" 'grep -qE "particle [0-9]+ left the domain at step [0-9]+ .*moved by system .integrate." "$tmp/err4"'
check "outputs written before the failure remain" '[ -f "$tmp/fall/stats.csv" ] && [ -f "$tmp/fall/summary.json" ]'

# 5. --help and --version.
"$run" --version | grep -q "sph-run" ; check "--version" '[ $? -eq 0 ]'
"$run" --help | grep -q -- "--graph" ; check "--help lists --graph" '[ $? -eq 0 ]'

[ $fail -eq 0 ] && echo "sph-run CLI: all checks passed"
exit $fail
