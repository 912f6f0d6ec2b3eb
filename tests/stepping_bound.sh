#!/usr/bin/env bash
# tools/stepping_bound.py end to end: the fewest evaluations per particle the acoustic condition
# allows, E0 = T / min(dt_max, Morris, lambda_c h / c_s), against the closed form on runs whose
# c_s, h and lambda_c the test sets itself, the Morris cap on a synthetic folder, and refusals
# that name the file. Each check prints what it expected.
set -uo pipefail
run=$1; src=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
check() { if ! eval "$2"; then echo "FAIL: $1"; fail=1; else echo "ok: $1"; fi; }
export PYTHONDONTWRITEBYTECODE=1
tool="$src/tools/stepping_bound.py"

# 1. Runs at lambda_c 0.8 (not the default, so a tool that assumed 0.4 fails) with c_s set to
#    25 m/s: the resting tank at a constant 0.25 ms, the dam break in `global` (0.3 s), and a run
#    without the acoustic condition.
C="--set simulation.stepping.lambda_c=0.8 --set fluid.speed_of_sound=25"
"$run" "$src/scenes/hydrostatic_tank.json" --mode constant --dt 2.5e-4 --end 0.2 --threads 2 --no-frames -q --out "$tmp/tank" $C; rc=$?
check "constant tank run exits 0 (got $rc)" '[ $rc -eq 0 ]'
"$run" "$src/scenes/dam_break.json" --mode global --end 0.3 --threads 2 --no-frames -q --out "$tmp/dam" $C; rc=$?
check "global dam break run exits 0 (got $rc)" '[ $rc -eq 0 ]'
"$run" "$src/scenes/dam_break.json" --mode global --end 0.01 --threads 2 --no-frames -q --out "$tmp/noac" \
  --set simulation.stepping.acoustic=false; rc=$?
check "acoustic-off run exits 0 (got $rc)" '[ $rc -eq 0 ]'

# 2. The figures against what they must be.
python3 - "$tool" "$tmp" <<'EOF'; rc=$?
import csv, importlib.util, json, pathlib, shutil, sys
spec = importlib.util.spec_from_file_location("stepping_bound", sys.argv[1])
sb = importlib.util.module_from_spec(spec); spec.loader.exec_module(sb)
tmp = pathlib.Path(sys.argv[2])
bad = []
def expect(cond, what):
    if not cond: bad.append(what)
h, c, lc = 4 * 0.01, 25.0, 0.8   # both scenes: r = 1 cm, h = 4 r (He et al.); c_s and lambda_c as set
dt_c = lc * h / c                # 1.28 ms, below dt_max (5 ms); no viscosity term (nu = 0)

# The tank at a constant 0.25 ms: 800 steps, every particle evaluated each step, so the ratio is
# dt_c / 0.25 ms = 5.12 (to the float h and the 1 ps tick).
b = sb.bound(str(tmp / "tank"))
print(f"tank: ratio {b['ratio']:.6f}, closed form {dt_c / 2.5e-4:.6f}")
expect(b["steps"] == 800, f"800 steps of 0.25 ms, got {b['steps']}")
expect(abs(b["ratio"] - dt_c / 2.5e-4) < 1e-6 * dt_c / 2.5e-4, f"tank ratio {b['ratio']} = {dt_c / 2.5e-4}")

# `global`: steps x dt_c / T. Step k is at most lambda_c h / (c_s + v_max,k) = dt_c / (1 + v_k / c_s)
# (v_max of its stats.csv row, what it was sized from) and the last, clipped to the end, at most
# dt_c, so the ratio is at least N / (sum_{k<N-1} 1 / (1 + v_k / c_s) + 1).
b = sb.bound(str(tmp / "dam"))
rows = list(csv.DictReader(open(tmp / "dam/stats.csv")))
N, T = len(rows), sum(float(r["dt"]) for r in rows)
lower = N / (sum(1 / (1 + float(r["v_max"]) / c) for r in rows[:-1]) + 1)
print(f"dam break: ratio {b['ratio']:.6f} over {b['steps']} steps, T {T:.6f} s, at least {lower:.6f}")
expect(abs(b["ratio"] - N * dt_c / T) < 1e-6 * b["ratio"], f"global ratio {b['ratio']} = {N * dt_c / T}")
expect(b["ratio"] >= lower * (1 - 1e-6), f"global ratio {b['ratio']} at least {lower}")
expect(abs(b["evaluations_per_particle"] - b["steps"]) < 1e-6, "global evaluates every particle at every step")

# A synthetic folder where Morris et al.'s viscous limit binds: h 0.04 m, nu 0.1 m^2/s gives
# 0.125 (h / 2)^2 / nu = 0.5 ms < lambda_c h / c_s = 2 ms; two steps of 1 ms, half the rows
# evaluated in the second: E0 = 2 ms / 0.5 ms = 4, ratio 1.5 / 4.
syn = tmp / "syn"; syn.mkdir()
(syn / "summary.json").write_text(json.dumps({
    "method": "wcsph", "stepping": "binned", "kept_steps": 2,
    "physics": {"support_radius": 0.04, "speed_of_sound": 20.0, "kinematic_viscosity": 0.1},
    "stepping_params": {"acoustic": True, "lambda_c": 1.0, "dt_max": 0.005}}))
(syn / "stats.csv").write_text("step,dt,active_fraction,v_max,rolled_back\n0,0.001,1,0,0\n1,0.001,0.5,0,0\n")
b = sb.bound(str(syn))
expect(abs(b["dt_c"] - 5e-4) < 1e-12 and abs(b["ratio"] - 1.5 / 4) < 1e-12, f"Morris cap: {b}")
# The same folder claiming three kept steps (a stats.csv that starts at a checkpoint) is refused.
part = tmp / "part"; shutil.copytree(syn, part)
s = json.loads((part / "summary.json").read_text()); s["kept_steps"] = 3
(part / "summary.json").write_text(json.dumps(s))
try:
    sb.bound(str(part)); bad.append("a stats.csv with fewer steps than kept_steps was accepted")
except sb.BadInput as e:
    expect("part/stats.csv: holds 2 steps of the run's 3" in str(e), f"partial stats message: {e}")
if bad:
    print("\n".join("FAIL: " + x for x in bad)); sys.exit(1)
EOF
check "ratios against the closed forms" '[ $rc -eq 0 ]'

# 3. Refusals exit 2 naming the file: no acoustic condition, no folder, a summary that is not one.
out=$(python3 "$tool" "$tmp/noac" 2>&1); rc=$?
check "acoustic off: exit 2 naming the file (got $rc: $out)" '[ $rc -eq 2 ] && [[ "$out" == *"noac/summary.json"*"acoustic condition is off"* ]]'
out=$(python3 "$tool" "$tmp/none" 2>&1); rc=$?
check "missing folder: exit 2 naming the file (got $rc: $out)" '[ $rc -eq 2 ] && [[ "$out" == *"none/summary.json"* ]]'
mkdir -p "$tmp/junk"; echo '[1, 2]' > "$tmp/junk/summary.json"
out=$(python3 "$tool" "$tmp/junk" 2>&1); rc=$?
check "a summary that is not an object: exit 2 naming the file (got $rc: $out)" '[ $rc -eq 2 ] && [[ "$out" == *"junk/summary.json"* ]]'
exit $fail
