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
check "adaptive with wcsph exits 2 naming the method (got $rc)" '[ $rc -eq 2 ] && grep -q "for method \"wcsph\" (\"adaptive\" is the PCISPH and DFSPH mode" "$tmp/err4"'
"$run" "$src/scenes/shock.json" --mode global --out "$tmp/bad5" 2>"$tmp/err5"; rc=$?
check "global with pcisph exits 2 naming the method (got $rc)" '[ $rc -eq 2 ] && grep -q "expected one of \"constant\", \"adaptive\" for method \"pcisph\"" "$tmp/err5"'
"$run" "$tmp/does_not_exist.json" 2>"$tmp/err3"; rc=$?
check "missing file exits 2 (got $rc)" '[ $rc -eq 2 ] && grep -q "cannot open scene file" "$tmp/err3"'

# 2b. The run folder's scene_as_run.json is the scene as run, overrides applied: run again from it (into
# another folder), the same steps, step sizes and densities to the bit.
"$run" "$src/scenes/dam_break.json" --end 0.03 --set fluid.viscosity=0.05 --mode binned --no-frames --out "$tmp/as_run" -q; rc1=$?
"$run" "$tmp/as_run/scene_as_run.json" --out "$tmp/again" -q; rc2=$?
check "a run from its scene_as_run.json exits 0 (got $rc1, $rc2)" '[ $rc1 -eq 0 ] && [ $rc2 -eq 0 ]'
check "scene_as_run.json holds the overrides (alpha 0.05, binned, end 0.03, no frames)" 'python3 -c "
import json, sys
s = json.load(open(\"$tmp/as_run/scene_as_run.json\"))
sys.exit(0 if s[\"fluid\"][\"viscosity\"] == 0.05 and s[\"simulation\"][\"stepping\"][\"mode\"] == \"binned\" and s[\"simulation\"][\"end_time\"] == 0.03 and s[\"simulation\"][\"frame_rate\"] == 0 else 1)"'
check "the run from scene_as_run.json repeats the run: t, dt, densities, active rows to the bit" 'python3 -c "
import csv, sys
cols = (\"step\", \"t\", \"dt\", \"rho_err_avg\", \"rho_err_max\", \"v_max\", \"active\", \"force_evaluations\")
a = [[r[c] for c in cols] for r in csv.DictReader(open(\"$tmp/as_run/stats.csv\"))]
b = [[r[c] for c in cols] for r in csv.DictReader(open(\"$tmp/again/stats.csv\"))]
sys.exit(0 if len(a) > 20 and a == b else 1)"'

# 2c. binned reduces its statistics over the due rows: stats.csv's whole_fluid marks the steps with
# every row due (and only those), and summary.json's max_avg_density_error is the largest
# rho_err_avg of those steps (the acoustic condition off: sleeping rows from the first steps).
"$run" "$src/scenes/dam_break.json" --end 0.03 --mode binned --set simulation.stepping.acoustic=false --no-frames --out "$tmp/whole" -q; rc=$?
check "binned: whole_fluid is 1 exactly on the steps with every row due, max_avg_density_error over them (exit $rc)" '[ $rc -eq 0 ] && python3 -c "
import csv, json, sys
s = json.load(open(\"$tmp/whole/summary.json\"))
rows = list(csv.DictReader(open(\"$tmp/whole/stats.csv\")))
flags = [int(r[\"whole_fluid\"]) == (int(r[\"active\"]) == s[\"fluid_particles\"]) for r in rows]
whole = [float(r[\"rho_err_avg\"]) for r in rows if r[\"whole_fluid\"] == \"1\"]
part = len(rows) - len(whole)
ok = all(flags) and whole and part > 0 and abs(s[\"max_avg_density_error\"] - max(whole)) <= 1e-8 * max(whole)
sys.exit(0 if ok else 1)"'

# A scene given by a relative path from elsewhere: its probes' experiment files (relative to the
# scene's folder) are written as absolute paths that exist.
(cd "$src/scenes/.." && "$run" scenes/martin_moyce.json --end 0.005 --no-frames --out "$tmp/mm" -q); rc=$?
check "scene_as_run.json's experiment files are absolute and exist (got $rc)" '[ $rc -eq 0 ] && python3 -c "
import json, os, sys
files = [p[\"experiment\"][\"file\"] for p in json.load(open(\"$tmp/mm/scene_as_run.json\"))[\"probes\"] if \"experiment\" in p]
sys.exit(0 if files and all(os.path.isabs(f) and os.path.isfile(f) for f in files) else 1)"'

# 3. A short good run writes stats.csv, summary.json, frames and the graph.
"$run" "$src/scenes/dam_break.json" --end 0.05 --out "$tmp/good" --graph "$tmp/g.dot" -q; rc=$?
check "short run exits 0 (got $rc)" '[ $rc -eq 0 ]'
check "summary.json reaches t = 0.05" 'python3 -c "import json,sys; s=json.load(open(\"$tmp/good/summary.json\")); sys.exit(0 if abs(s[\"simulated_time_s\"]-0.05)<1e-9 and s[\"steps\"]>10 and s[\"fluid_particles\"]==8000 else 1)"'
check "stats.csv has one row per step" 'python3 -c "import json,sys; s=json.load(open(\"$tmp/good/summary.json\")); n=len(open(\"$tmp/good/stats.csv\").read().splitlines())-1; sys.exit(0 if n==s[\"steps\"] else 1)"'
# The engine's re-sort (every 16 steps in global) is the last column, positive exactly on those
# steps; its total is summary.json's spatial_sort_s (the column holds 4 significant digits).
check "ms_spatial_sort: the sorting steps, summed in spatial_sort_s" 'python3 -c "
import csv, json, sys
rows = list(csv.DictReader(open(\"$tmp/good/stats.csv\")))
s = json.load(open(\"$tmp/good/summary.json\"))
ok = list(rows[0])[-1] == \"ms_spatial_sort\" and all((float(r[\"ms_spatial_sort\"]) > 0) == (int(r[\"step\"]) % 16 == 0) for r in rows)
total = sum(float(r[\"ms_spatial_sort\"]) for r in rows) / 1e3
sys.exit(0 if ok and abs(total - s[\"spatial_sort_s\"]) <= 1e-3 * s[\"spatial_sort_s\"] + 1e-9 else 1)"'
check "frames at 30 fps: t = 0 and one more" '[ -f "$tmp/good/frames/frame_00000.vtu" ] && [ -f "$tmp/good/frames/frame_00001.vtu" ]'
check "graph has the WCSPH nodes" 'grep -q "forces" "$tmp/g.dot" && grep -q -- "->" "$tmp/g.dot"'
check "no temporary files left" '[ -z "$(find "$tmp/good" -name "*.tmp*")" ]'

# 3b. Every frame format at once: .vtu, .bgeo and .ply per frame, attributes as chosen.
"$run" "$src/scenes/dam_break.json" --end 0.04 --out "$tmp/fmt" -q --set 'output.format=["vtu","bgeo","ply"]' \
  --set 'output.attributes=["velocity","dt","active"]'; rc=$?
check "three formats run exits 0 (got $rc)" '[ $rc -eq 0 ]'
check "frames 0 and 1 in .vtu, .bgeo and .ply" 'for f in 00000 00001; do for e in vtu bgeo ply; do [ -s "$tmp/fmt/frames/frame_$f.$e" ] || exit 1; done; done'
check "PLY header lists the chosen attributes" 'head -c 400 "$tmp/fmt/frames/frame_00001.ply" | grep -a -q "property float velocity_x" && head -c 400 "$tmp/fmt/frames/frame_00001.ply" | grep -a -q "property double dt" && ! head -c 400 "$tmp/fmt/frames/frame_00001.ply" | grep -a -q density'
check "BGEO starts with BgeoV" '[ "$(head -c 5 "$tmp/fmt/frames/frame_00001.bgeo")" = "BgeoV" ]'

# 3b. The surface only (format mesh): surface/surface_NNNNN.ply per frame, no particle frames,
# the walls as .ply (no particle format to follow), its cost in summary.json and the last line.
"$run" "$src/scenes/dam_break.json" --end 0.04 --format mesh --out "$tmp/surf" >"$tmp/err_surf" 2>&1; rc=$?
check "surface-only run exits 0 (got $rc)" '[ $rc -eq 0 ]'
check "surface/surface_00000.ply and _00001.ply, no frames/" '[ -s "$tmp/surf/surface/surface_00000.ply" ] && [ -s "$tmp/surf/surface/surface_00001.ply" ] && [ ! -e "$tmp/surf/frames" ] && [ ! -e "$tmp/surf/frames.pvd" ]'
check "walls as .ply" '[ -s "$tmp/surf/boundary/walls.ply" ]'
check "summary.json has the surface cost" 'grep -q "\"seconds_per_frame\"" "$tmp/surf/summary.json"'
check "last lines name surface/ and the cost per frame" 'grep -q "(mesh) to $tmp/surf/surface," "$tmp/err_surf" && grep -q "surfaces: .* s per frame" "$tmp/err_surf"'

# 3c. A fluid block whose sides are not multiples of the spacing: a warning with the shortfall.
"$run" "$src/scenes/dam_break.json" --end 0.001 --no-frames --out "$tmp/fill" \
  --set 'fluid_blocks=[{"min":[0,0,0],"max":[0.41,0.79,0.2]}]' >"$tmp/fill.log" 2>&1; rc=$?
check "a block of 0.41 x 0.79 x 0.2 m at 2 cm spacing: runs, warns 3.7 % less water (exit $rc)" '[ $rc -eq 0 ] && grep -q "/fluid_blocks/0: 20 x 39 x 10 = 7800 particles hold 0.0624 m^3 of water, 3.7 % less than the block.s 0.06478 m^3" "$tmp/fill.log"'

# 3d. lambda_c above the stable edge (stable_lambda_c: 0.8 summation, 0.7 continuity): a warning naming
# the key, the value and the edge; at the edge itself, none.
"$run" "$src/scenes/dam_break.json" --end 0.001 --no-frames --out "$tmp/lc" --set simulation.stepping.lambda_c=0.9 >"$tmp/lc.log" 2>&1; rc=$?
check "lambda_c 0.9 with the summation density: runs, warns above 0.8 (exit $rc)" '[ $rc -eq 0 ] && grep -q "simulation.stepping.lambda_c = 0.9 is above 0.8, the largest at which a summation density" "$tmp/lc.log"'
"$run" "$src/scenes/dam_break.json" --end 0.001 --no-frames --out "$tmp/lc" --set simulation.stepping.lambda_c=0.8 --set fluid.density=continuity >"$tmp/lc2.log" 2>&1; rc=$?
check "lambda_c 0.8 with the continuity density: warns above 0.7 (exit $rc)" '[ $rc -eq 0 ] && grep -q "lambda_c = 0.8 is above 0.7, the largest at which a continuity density" "$tmp/lc2.log"'
"$run" "$src/scenes/dam_break.json" --end 0.001 --no-frames --out "$tmp/lc" --set simulation.stepping.lambda_c=0.8 >"$tmp/lc3.log" 2>&1; rc=$?
check "lambda_c 0.8 with the summation density: no warning (exit $rc)" '[ $rc -eq 0 ] && ! grep -q "lambda_c = 0.8 is above" "$tmp/lc3.log"'

# 4. A particle leaving the domain: exit 3 naming the particle, the step and the system.
"$run" "$src/tests/data/valid/falls_out.json" --out "$tmp/fall" 2>"$tmp/err4"; rc=$?
check "leaving the domain exits 3 (got $rc)" '[ $rc -eq 3 ]'
check "diagnosis names particle, step and system" 'grep -qE "particle [0-9]+ left the domain at step [0-9]+ .*moved by system .integrate." "$tmp/err4"'
check "outputs written before the failure remain" '[ -f "$tmp/fall/stats.csv" ] && [ -f "$tmp/fall/summary.json" ]'

# 4b. A NaN injected into particle 5 in step 3: exit 3 naming that particle, step and system.
"$run" "$src/scenes/dam_break.json" --end 0.01 --inject-nan 3:5 --out "$tmp/nan" -q 2>"$tmp/err5"; rc=$?
check "injected NaN exits 3 (got $rc)" '[ $rc -eq 3 ]'
check "diagnosis names particle 5, step 3 and inject_nan" 'grep -q "particle 5 became non-finite at step 3 (t = .*): acceleration is NaN or infinite, first produced by system .inject_nan." "$tmp/err5"'
check "frames written before the NaN remain complete" '[ -f "$tmp/nan/frames/frame_00000.vtu" ] && [ -z "$(find "$tmp/nan" -name "*.tmp*")" ]'
check "summary.json is marked failed with the reason, the step and the run's threads" \
  'python3 -c "import json, sys; j = json.load(open(\"$tmp/nan/summary.json\")); f = j[\"failed\"]; sys.exit(0 if \"particle 5 became non-finite\" in f[\"reason\"] and f[\"step\"] == 3 and j[\"threads\"] >= 1 and j[\"wall_time_s\"] > 0 else 1)"'
"$run" "$src/scenes/dam_break.json" --inject-nan 3 --out "$tmp/nan2" 2>"$tmp/err6"; rc=$?
check "malformed --inject-nan exits 2 (got $rc)" '[ $rc -eq 2 ] && grep -q "expected STEP:ID" "$tmp/err6" && [ ! -e "$tmp/nan2" ]'
# A run into a folder that holds an earlier run's outputs, failing in its set-up (after the scene
# loaded: here the --inject-nan argument, and an unwritable --graph path), leaves them as they were.
ls -R "$tmp/nan" > "$tmp/nan.before"
"$run" "$src/scenes/dam_break.json" --inject-nan 1:2:3 --out "$tmp/nan" 2>"$tmp/err7"; rc=$?
"$run" "$src/scenes/dam_break.json" --graph /proc/none/g.dot --out "$tmp/nan" 2>"$tmp/err8"; rc8=$?
check "set-up failures (exit $rc, $rc8) leave the earlier run's outputs" \
  '[ $rc -eq 2 ] && [ $rc8 -eq 5 ] && cmp -s "$tmp/nan.before" <(ls -R "$tmp/nan") && grep -q "particle 5" "$tmp/nan/summary.json"'

# 4c. Another method's section is still checked when --method replaces the scene's: a bad value
#     set into it is an error naming the key, and a PCISPH scene runs as DFSPH with its own
#     pcisph section left unused.
"$run" "$src/scenes/dam_break.json" --method wcsph --set dfsph.eta=abc --end 0.002 --out "$tmp/m1" -q 2>"$tmp/err9"; rc=$?
check "--method with a bad value in another method's section exits 2 naming it (got $rc)" \
  '[ $rc -eq 2 ] && grep -q "/dfsph/eta: found \"abc\", expected a number" "$tmp/err9" && [ ! -e "$tmp/m1" ]'
"$run" "$src/scenes/glass.json" --method dfsph --end 0.002 --out "$tmp/m2" -q; rc=$?
check "a PCISPH scene with --method dfsph runs (got $rc)" '[ $rc -eq 0 ]'

# 4d. Flags that contradict each other are refused, not resolved by their order.
"$run" "$src/scenes/dam_break.json" --no-frames --frame-rate 100 --out "$tmp/m3" 2>"$tmp/err10"; rc=$?
check "--no-frames with --frame-rate exits 2 (got $rc)" '[ $rc -eq 2 ] && grep -q "excludes" "$tmp/err10" && [ ! -e "$tmp/m3" ]'

# 5. --help and --version.
# (The output is captured first: `| grep -q` under pipefail fails when grep exits early and the
# writer dies of SIGPIPE.)
out_version=$("$run" --version); rc_version=$?
check "--version (exit $rc_version)" '[ $rc_version -eq 0 ] && [[ "$out_version" == *"sph-run"* ]]'
out_help=$("$run" --help); rc_help=$?
check "--help lists --graph (exit $rc_help)" '[ $rc_help -eq 0 ] && [[ "$out_help" == *"--graph"* ]]'

[ $fail -eq 0 ] && echo "sph-run CLI: all checks passed"
exit $fail
