#!/usr/bin/env bash
# tools/resolution_study.py end to end on tiny Martin & Moyce runs (spacing a/6 and a/8, three
# perturbed runs each, 0.12 s simulated): the particle counts follow the refinement (216 and
# 512), and every error the tool reports is recomputed here from the runs' probe files by brute
# force (every shift on the 0.005 grid; its own mean curve and differences on the experiment's
# times), so a wrong shift sign, a wrong scaling or a wrong average fails. Tolerances: the
# per-run errors use the same shift grid and must agree to 1e-9; the mean-curve figures are
# computed here on a different time grid (the union of the runs' sample times instead of 2,000
# even points), which moves them by the linear-interpolation error of 2 ms probe samples, under
# 1 % of the value (+ 0.02 percentage points), far below the effects a bug would have.
# usage: resolution_study.sh SOURCE_DIR SPH_RUN
set -euo pipefail
src=$1; sph_run=$2
out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
cd "$src"
/usr/bin/python3 tools/resolution_study.py scenes/martin_moyce.json --refine 0.6667,0.5 --runs 3 --end 0.12 \
    --sph-run "$sph_run" --out "$out/r" > "$out/log" 2>&1 || { cat "$out/log"; exit 1; }
grep -q "\[6/6\] refine 0.6667" "$out/log"
/usr/bin/python3 - "$out/r" <<'PY'
import csv, json, pathlib, sys
import numpy as np
d = pathlib.Path(sys.argv[1])
scene = json.load(open("scenes/martin_moyce.json"))
rows = list(csv.DictReader(open(d / "resolution.csv")))
probes = [p for p in scene["probes"] if "experiment" in p]
assert [r["probe"] for r in rows] == [p["name"] for p in probes for _ in (0, 1)], rows
def load(path):
    lines = [l for l in open(path) if l.strip() and not l.startswith("#")]
    head = lines[0].strip().split(",")
    a = np.array([[float(c) for c in l.split(",")] for l in lines[1:]])
    return {h: a[:, i] for i, h in enumerate(head)}
def err(T, Z, te, ze, lo, hi, m):  # every shift the run covers without extrapolating
    sel = (te >= lo) & (te <= hi) & (te - m <= T[-1])
    best = (1e9, 0)
    for k in range(-round(m / 0.005), round(m / 0.005) + 1):
        t = te[sel] - 0.005 * k
        if T[0] <= t.min() and t.max() <= T[-1]:
            e = (np.interp(t, T, Z) - ze[sel]) / ze[sel]
            best = min(best, (np.sqrt(np.mean(e ** 2)), 0.005 * k))
    return best
for p in probes:
    e = p["experiment"]
    x = load(pathlib.Path("scenes") / e["file"])
    te, ze = list(x.values())[0], list(x.values())[1]
    col = "height" if p["type"] == "height" else "front"
    lo, hi = e["t_range"]
    prev = None
    for f, n in (("0.5", 216), ("0.6667", 512)):
        r = next(r for r in rows if r["probe"] == p["name"] and float(r["refine"]) == float(f))
        assert int(r["particles"]) == n and int(r["runs"]) == 3, r
        series = []
        for k in range(3):
            s = load(d / f"f{f}" / f"run{k}" / "probes" / f"{p['name']}.csv")
            series.append((s["t"] * e["t_scale"], s[col] * e["value_scale"]))
        per_run = sorted(err(T, Z, te, ze, lo, hi, e["max_shift"])[0] for T, Z in series)
        for key, want in (("err_min", per_run[0]), ("err_median", per_run[1]), ("err_max", per_run[2])):
            assert abs(float(r[key]) - want) < 1e-9, (p["name"], f, key, r[key], want)
        t_end = min(T[-1] for T, _ in series)
        inside = (te >= lo) & (te <= hi) & (te <= t_end)
        mx = sorted(np.max(np.abs(np.interp(te[inside], T, Z) - ze[inside])) for T, Z in series)
        for key, want in (("max_abs_min", mx[0]), ("max_abs_median", mx[1]), ("max_abs_max", mx[2])):
            assert abs(float(r[key]) - want) < 1e-9, (p["name"], f, key, r[key], want)
        grid = np.unique(np.concatenate([T[T <= t_end] for T, _ in series]))
        mean = np.mean([np.interp(grid, T, Z) for T, Z in series], axis=0)
        got = float(r["mean_err"])
        shifted = err(grid, mean, te, ze, lo, hi, e["max_shift"])[0]
        assert abs(got - shifted) <= 0.01 * shifted + 2e-4, (p["name"], f, got, shifted)
        w = (grid >= lo) & (grid <= hi)
        if prev is None:
            assert r["change"] == "nan", r
        else:
            ch = np.sqrt(np.mean(((np.interp(grid[w], *prev) - mean[w]) / mean[w]) ** 2))
            assert abs(float(r["change"]) - ch) <= 0.02 * ch + 2e-4, (p["name"], r["change"], ch)
        prev = (grid, mean)
        assert abs(float(r["mean_shift"])) <= e["max_shift"] + 1e-12 and abs(float(r["free_shift"])) <= 1 + 1e-12
        assert float(r["free_err"]) <= float(r["mean_err"]) + 1e-12   # a wider search cannot do worse
md = (d / "resolution.md").read_text()
assert md.count("\n| 7.14 mm |") == len(probes) and "3 run(s) per resolution" in md, md
b = (d / "resolution.png").read_bytes()
assert b[:8] == b"\x89PNG\r\n\x1a\n" and len(b) > 10000
print("resolution_study: ok")
PY
# bad input: a clear error naming the option, exit 2, nothing run
for bad in "--refine 1,x" "--refine 0,1" "--perturb lambda_c" "--runs 0" "--vary fluid.support=2"; do
    set +e; /usr/bin/python3 tools/resolution_study.py scenes/martin_moyce.json $bad --sph-run "$sph_run" \
        --out "$out/bad" > "$out/bad.log" 2>&1; rc=$?; set -e
    [ "$rc" = 2 ] || { echo "'$bad': exit $rc, expected 2"; cat "$out/bad.log"; exit 1; }
    grep -q "resolution_study.py: error: ${bad%% *}" "$out/bad.log" || { echo "'$bad':"; cat "$out/bad.log"; exit 1; }
done
# An experiment file that is missing or has one column stops the study before any run (exit 2,
# one line naming the probe and the file), read once for all runs.
printf 't\n0.1\n0.2\n' > "$out/one_column.csv"
for file in "$out/one_column.csv" "$out/no_such.csv"; do
    /usr/bin/python3 -c "
import json, sys
s = json.load(open('scenes/martin_moyce.json'))
s['probes'][0]['experiment']['file'] = sys.argv[2]
json.dump(s, open(sys.argv[1], 'w'))" "$out/exp.json" "$file"
    rc=0; /usr/bin/python3 tools/resolution_study.py "$out/exp.json" --runs 1 --refine 0.5 --end 0.01 \
        --sph-run "$sph_run" --out "$out/exp" > "$out/exp.log" 2>&1 || rc=$?
    [ "$rc" = 2 ] && [ ! -e "$out/exp" ] && ! grep -q Traceback "$out/exp.log" \
        && grep -q "^resolution_study.py: error: .*exp.json: probe 'front': experiment file $file: " "$out/exp.log" \
        || { echo "experiment file $file: exit $rc, expected 2 before any run"; cat "$out/exp.log"; exit 1; }
done
echo "resolution_study bad input: ok"

# Runs whose output cannot be read (tests/fake_sph_run.sh: run1's summary.json truncated, run2's
# probe files cut mid-row) are left out of their resolution's figures and named in its status;
# the table keeps run0's figures, and the study exits 2 naming both runs after writing it.
fake=$src/tests/fake_sph_run.sh
export FAKE_REAL=$sph_run
tiny=(scenes/martin_moyce.json --refine 0.5 --runs 3 --end 0.06 --sph-run "$fake")
rc=0; FAKE_RULES='*/f0.5/run1:truncate-summary */f0.5/run2:truncate-probes' \
    /usr/bin/python3 tools/resolution_study.py "${tiny[@]}" --out "$out/u" > "$out/u.log" 2>&1 || rc=$?
[ "$rc" = 2 ] && ! grep -q Traceback "$out/u.log" \
    && grep -q "^resolution_study.py: error: 2 of 3 run(s) not usable (refine 0.5 run1: unreadable: .*run1/summary.json: not valid JSON" "$out/u.log" \
    || { echo "unreadable runs: exit $rc, expected 2 and the message"; cat "$out/u.log"; exit 1; }
/usr/bin/python3 - "$out/u" <<'PY'
import csv, pathlib, sys
d = pathlib.Path(sys.argv[1])
rows = list(csv.DictReader(open(d / "resolution.csv")))
assert [r["probe"] for r in rows] == ["front", "front_colour", "residual_height"], rows
for r in rows:
    assert r["runs"] == "1" and r["particles"] == "216" and r["err_min"] == r["err_max"] == r["err_median"], r
    assert r["status"].startswith(f"1 of 3 runs usable; run1: unreadable: {d}/f0.5/run1/summary.json: not valid JSON"), r
    assert f"; run2: unreadable: {d}/f0.5/run2/probes/" in r["status"] and ".csv: line 6: cut short" in r["status"], r
md = (d / "resolution.md").read_text()
assert md.count("\n| 9.53 mm |") == 3 and md.count("\n* refine 0.5: 1 of 3 runs usable; run1: unreadable: ") == 3, md
assert (d / "resolution.png").is_file()
print("resolution_study unreadable runs: ok")
PY

# A crash after the first run (the fake kills the tool as the second starts): the table holds
# the first run's figures, marked as a resolution not finished.
rc=0; FAKE_RULES='*/f0.5/run1:kill-tool' /usr/bin/python3 tools/resolution_study.py "${tiny[@]}" --out "$out/k" \
    > "$out/k.log" 2>&1 || rc=$?
[ "$rc" = 137 ] || { echo "killed study: exit $rc, expected 137"; cat "$out/k.log"; exit 1; }
/usr/bin/python3 - "$out/k" <<'PY'
import csv, pathlib, sys
d = pathlib.Path(sys.argv[1])
rows = list(csv.DictReader(open(d / "resolution.csv")))
assert [(r["probe"], r["runs"], r["status"]) for r in rows] == \
    [(p, "1", "1 of 3 runs run so far") for p in ("front", "front_colour", "residual_height")], rows
assert all(float(r["err_median"]) > 0 for r in rows), rows
assert (d / "resolution.md").read_text().count("\n| 9.53 mm |") == 3
print("resolution_study killed after one run: ok")
PY

# A run sph-run reports failed (the fake exits 3): a row "failed (exit 3)" with no figures, exit 2.
rc=0; FAKE_RULES='*/f0.5/run0:fail' /usr/bin/python3 tools/resolution_study.py "${tiny[@]}" --runs 1 \
    --out "$out/f" > "$out/f.log" 2>&1 || rc=$?
[ "$rc" = 2 ] && ! grep -q Traceback "$out/f.log" \
    && grep -q "^resolution_study.py: error: 1 of 1 run(s) not usable (refine 0.5 run0: failed (exit 3))" "$out/f.log" \
    && [ "$(cut -d, -f1,6,21 "$out/f/resolution.csv" | tr -d '\r' | tr '\n' ' ')" = "probe,runs,status$(for p in front front_colour residual_height; do printf ' %s,0,0 of 1 runs usable; run0: failed (exit 3)' $p; done) " ] \
    && grep -q "^| refine 0.5 | 0 of 1 runs usable; run0: failed (exit 3) |" "$out/f/resolution.md" \
    || { echo "failed run: exit $rc, expected 2 and a failed row"; cat "$out/f.log" "$out/f/resolution.csv"; exit 1; }
echo "resolution_study failed run: ok"
