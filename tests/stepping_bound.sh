#!/usr/bin/env bash
# tools/stepping_bound.py end to end: the fewest evaluations per particle the acoustic condition
# allows, E0 = sum_k dt_k max(1 / cap, (c_s + vbar_k) / (lambda_c h)), against bounds that follow
# from the runs' own step rules on runs whose c_s, h and lambda_c the test sets itself, closed
# forms on synthetic folders (the Morris cap, the mean speeds), and refusals that name the file.
# Each check prints what it expected.
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

# The tank at a constant 0.25 ms: 800 steps, every particle evaluated each step. At rest the
# ratio would be dt_c / 0.25 ms = 5.12 (to the float h and the 1 ps tick); the tank settles from
# its lattice, so each step's floor rises by 1 + vbar / c_s with vbar <= v_max, and the ratio lies
# between 5.12 / (1 + max v_max / c_s) and 5.12, below it by the mean speed (nonzero: v_mean read).
b = sb.bound(str(tmp / "tank"))
rows = list(csv.DictReader(open(tmp / "tank/stats.csv")))
vmax = max(float(r["v_max"]) for r in rows)
rest = dt_c / 2.5e-4
print(f"tank: ratio {b['ratio']:.6f}, at rest {rest:.6f}, at least {rest / (1 + vmax / c):.6f}")
expect(b["steps"] == 800, f"800 steps of 0.25 ms, got {b['steps']}")
expect(abs(b["bound_at_rest"] * rest - 800) < 1e-6 * 800, f"tank floor at rest {b['bound_at_rest']} = 800 / {rest}")
expect(rest / (1 + vmax / c) * (1 - 1e-9) <= b["ratio"] < rest, f"tank ratio {b['ratio']} in [{rest / (1 + vmax / c)}, {rest})")
expect(b["speed_share"] == 1.0, f"every step of a constant run has v_mean: {b['speed_share']}")

# `global`: step k is at most lambda_c h / (c_s + v_max,k) (v_max of its stats.csv row, what it was
# sized from) and the last, clipped to the end, at most that too; a step's floor is
# dt_k (c_s + vbar_k) / (lambda_c h) <= (c_s + vbar_k) / (c_s + v_max,k) evaluations, so the ratio is
# at least N / sum_k (c_s + vbar_k) / (c_s + v_max,k), at least 1 (vbar <= v_max), and below
# the ratio at rest, N dt_c / T, by the mean speeds (> 0 in a dam break).
b = sb.bound(str(tmp / "dam"))
rows = list(csv.DictReader(open(tmp / "dam/stats.csv")))
N, T = len(rows), sum(float(r["dt"]) for r in rows)
vbar = [float(r["v_mean"]) for r in rows]
expect(all(0 <= vb <= float(r["v_max"]) * (1 + 1e-6) for vb, r in zip(vbar, rows)), "0 <= v_mean <= v_max on every row")
lower = N / sum((c + vb) / (c + float(r["v_max"])) for vb, r in zip(vbar, rows))
print(f"dam break: ratio {b['ratio']:.6f} over {b['steps']} steps, T {T:.6f} s, at least {lower:.6f}, "
      f"at rest {N * dt_c / T:.6f}, mean speed {sum(vbar) / N:.4f} m/s")
expect(lower * (1 - 1e-6) <= b["ratio"] < N * dt_c / T, f"global ratio {b['ratio']} in [{lower}, {N * dt_c / T})")
expect(lower >= 1, f"the lower bound {lower} is at least 1")
expect(abs(b["bound_at_rest"] - T / dt_c) < 1e-6 * b["bound_at_rest"], f"floor at rest {b['bound_at_rest']} = T / dt_c")
expect(abs(b["evaluations_per_particle"] - b["steps"]) < 1e-6, "global evaluates every particle at every step")

# A synthetic folder where Morris et al.'s viscous limit binds: h 0.04 m, nu 0.1 m^2/s gives
# 0.125 (h / 2)^2 / nu = 0.5 ms < lambda_c h / c_s = 2 ms; two steps of 1 ms, half the rows
# evaluated in the second: E0 = 2 ms / 0.5 ms = 4, ratio 1.5 / 4.
def synthetic(name, kept, nu, stats):
    """A binned run folder: h 0.04 m, c_s 20 m/s, lambda_c 1, dt_max 5 ms, the given nu and stats.csv."""
    d = tmp / name; d.mkdir()
    (d / "summary.json").write_text(json.dumps({
        "method": "wcsph", "stepping": "binned", "kept_steps": kept,
        "physics": {"support_radius": 0.04, "speed_of_sound": 20.0, "kinematic_viscosity": nu},
        "stepping_params": {"acoustic": True, "lambda_c": 1.0, "dt_max": 0.005}}))
    (d / "stats.csv").write_text(stats)
    return d
syn = synthetic("syn", 2, 0.1, "step,dt,active_fraction,v_max,rolled_back\n0,0.001,1,0,0\n1,0.001,0.5,0,0\n")
b = sb.bound(str(syn))
expect(abs(b["dt_c"] - 5e-4) < 1e-12 and abs(b["ratio"] - 1.5 / 4) < 1e-12, f"Morris cap: {b}")
# Mean speeds: h 0.04 m, c_s 20 m/s, lambda_c 1, no viscosity, dt_max 5 ms, so the bound is
# 0.04 / (20 + vbar) s. Three 1 ms steps: every row at vbar 5 m/s (1 ms x 25 / 0.04 = 0.625
# evaluations), every row at 60 m/s (2.0), half the rows at 60 m/s (not the whole fluid's mean:
# counted at rest, 0.5): E0 = 3.125, made 2.5.
spd = synthetic("spd", 3, 0.0, "step,dt,active_fraction,v_max,v_mean\n0,0.001,1,9,5\n1,0.001,1,80,60\n2,0.001,0.5,80,60\n")
b = sb.bound(str(spd))
expect(abs(b["bound_evaluations_per_particle"] - 3.125) < 1e-12 and abs(b["ratio"] - 2.5 / 3.125) < 1e-12
       and abs(b["bound_at_rest"] - 1.5) < 1e-12 and abs(b["speed_share"] - 2 / 3) < 1e-12, f"mean speeds: {b}")
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
