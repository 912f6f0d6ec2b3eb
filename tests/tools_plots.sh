#!/usr/bin/env bash
# Frames and plots of individual time stepping, end to end: a short dam break in `individual`
# mode writes frames whose dt/active arrays agree with stats.csv and summary.json; render_dt.py
# and plot_dt.py draw them with the stated size and colours; bad input exits 2 naming the file.
# Then mode_table.py and boundary_sweep.py on tiny runs whose output a fake sph-run spoils or
# during which it kills the tool: the tables keep every readable row (section 6).
# Each check prints what it expected when it fails.
set -uo pipefail
run=$1; src=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
check() { if ! eval "$2"; then echo "FAIL: $1"; fail=1; else echo "ok: $1"; fi; }

# A python with numpy and matplotlib (tools/install_deps.sh installs Debian's; a pyenv or
# virtualenv python3 first on PATH may lack them).
py=""
for c in python3 /usr/bin/python3; do
  if "$c" -c "import numpy, matplotlib" 2>/dev/null; then py=$c; break; fi
done
if [ -z "$py" ]; then echo "FAIL: no python3 with numpy and matplotlib (run: bash tools/install_deps.sh)"; exit 1; fi
export PYTHONPATH="$src/tools" MPLBACKEND=Agg MPLCONFIGDIR="$tmp/mpl" PYTHONDONTWRITEBYTECODE=1

# 1. Runs: 0.1 s of dam_break in individual mode (frames at 0, 1/30, 2/30, 0.1 s) and a
#    0.01 s global run (frame at t = 0 only).
"$run" "$src/scenes/dam_break.json" --mode individual --end 0.1 --threads 2 --out "$tmp/ind" -q; rc=$?
check "individual run exits 0 (got $rc)" '[ $rc -eq 0 ]'
"$run" "$src/scenes/dam_break.json" --mode global --end 0.01 --threads 2 --out "$tmp/glob" -q; rc=$?
check "global run exits 0 (got $rc)" '[ $rc -eq 0 ]'

# 2. Frame contents against stats.csv and summary.json.
"$py" - "$tmp" <<'EOF'; rc=$?
import csv, json, pathlib, sys
import numpy as np
from sph_vtu import read_vtu
tmp = pathlib.Path(sys.argv[1])
rows = list(csv.DictReader(open(tmp / "ind/stats.csv")))
summary = json.load(open(tmp / "ind/summary.json"))
files = sorted((tmp / "ind/frames").glob("*.vtu"))
bad = []
def expect(cond, what):
    if not cond: bad.append(what)
expect(len(files) == 4, f"4 frames (t = 0, 1/30, 2/30, 0.1 s), found {len(files)}")
for f in files:
    fr = read_vtu(f)
    expect(fr.types.get("dt") == "Float64" and fr.types.get("active") == "UInt8",
           f"{f.name}: dt Float64 and active UInt8, found {fr.types}")
    if "dt" not in fr.point_data or "active" not in fr.point_data:
        continue
    dt, act = fr.point_data["dt"], fr.point_data["active"]
    expect(fr.n == summary["fluid_particles"] == 8000, f"{f.name}: 8000 points, found {fr.n}")
    expect(set(np.unique(act).tolist()) <= {0, 1}, f"{f.name}: active is 0 or 1")
    if fr.time == 0:
        expect(not dt.any() and not act.any(), f"{f.name}: at t = 0 no step taken yet: dt = 0, active = 0")
        continue
    # The frame is written after the step that ends on its time: that stats row.
    match = [r for r in rows if abs(float(r["t"]) + float(r["dt"]) - fr.time) < 1e-9]
    expect(len(match) == 1, f"{f.name}: one stats row ending at t = {fr.time!r}, found {len(match)}")
    if len(match) != 1:
        continue
    r = match[0]
    expect(int(act.sum()) == int(r["active"]), f"{f.name}: active count {int(act.sum())} == stats active {r['active']} (step {r['step']})")
    expect(abs(act.mean() - float(r["active_fraction"])) < 1e-8, f"{f.name}: active fraction {act.mean()} == {r['active_fraction']}")
    # Delta t_sim = min_i Delta t_i (He Alg. 2 line 17), quantised down to 1 ps ticks, CSV at 9 digits;
    # under `activation: deadline` (the default) the step also stops at the earliest deadline of a
    # sleeping particle, never below the last stable step, which is at least the previous row's
    # dt: so dt = min dt_i, or a shorter step no shorter than the previous one. The last step is
    # clipped to the end time, so only bounded by the minimum.
    row_dt = float(r["dt"])
    if r is not rows[-1]:
        prev_dt = float(rows[rows.index(r) - 1]["dt"])
        tol = 2e-12 + 1e-9 * dt.min()
        expect(row_dt <= dt.min() + tol and (abs(dt.min() - row_dt) <= tol or row_dt >= prev_dt - tol),
               f"{f.name}: stats dt {row_dt!r} == min dt_i {dt.min()!r}, or below it and >= the previous step {prev_dt!r}")
    else:
        expect(row_dt <= dt.min() * (1 + 1e-9), f"{f.name}: clipped last step {row_dt!r} <= min dt_i {dt.min()!r}")
    expect(summary["min_dt_s"] * (1 - 1e-12) <= dt.min() <= summary["max_dt_s"] * (1 + 1e-12),
           f"{f.name}: min dt_i {dt.min()!r} within summary [{summary['min_dt_s']!r}, {summary['max_dt_s']!r}]")
    expect(dt.min() > 0 and dt.max() <= 5e-3 and dt.max() > 1.5 * dt.min(),
           f"{f.name}: 0 < dt_i <= dt_max 5 ms and spread (found {dt.min()!r} .. {dt.max()!r})")
g = read_vtu(tmp / "glob/frames/frame_00000.vtu")
expect("dt" not in g.point_data and "active" not in g.point_data, f"global frame has no dt/active, found {list(g.point_data)}")
for b in bad: print("  expected:", b)
sys.exit(1 if bad else 0)
EOF
check "frames carry dt (Float64) and active (UInt8) equal to stats.csv/summary.json" '[ $rc -eq 0 ]'

# 3. render_dt.py: sizes and colours.
"$py" "$src/tools/render_dt.py" "$tmp/ind" --out "$tmp/png" --width 640 >"$tmp/render.out" 2>&1; rc=$?
check "render_dt.py exits 0 (got $rc: $(tail -1 "$tmp/render.out"))" '[ $rc -eq 0 ]'
check "render_dt.py wrote 4 PNGs" '[ "$(ls "$tmp/png"/*.png 2>/dev/null | wc -l)" -eq 4 ]'
"$py" - "$tmp" <<'EOF'; rc=$?
import pathlib, re, sys
import numpy as np
import matplotlib.image as mpimg
import render_dt
from sph_vtu import read_vtu
tmp = pathlib.Path(sys.argv[1])
bad = []
def expect(cond, what):
    if not cond: bad.append(what)
m = re.search(r"images (\d+) x (\d+) px", (tmp / "render.out").read_text())
W, H = int(m.group(1)), int(m.group(2))
expect(W == 640, f"stated width 640, printed {W}")
frames = [read_vtu(f) for f in sorted((tmp / "ind/frames").glob("*.vtu"))]
lo, hi = render_dt.view_bounds(frames, 0, 1)
layout = render_dt.Layout(lo, hi, 640)
expect(layout.height == H, f"layout height {layout.height} == printed {H}")
pos = np.concatenate([f.point_data["dt"][f.point_data["dt"] > 0] for f in frames])
lo_dt, hi_dt = pos.min(), pos.max()
# The colour map itself: smallest -> (1, 0, 0), largest -> (1, 1, 1), monotonic in between (log).
grid = np.geomspace(lo_dt, hi_dt, 50)
c = render_dt.dt_colours(grid, lo_dt, hi_dt)
expect(np.allclose(c[0], (1, 0, 0), atol=1e-6) and np.allclose(c[-1], (1, 1, 1), atol=1e-6), f"ends red/white, got {c[0]}, {c[-1]}")
expect(np.all(np.diff(c[:, 1]) > 0) and np.allclose(c[:, 1], c[:, 2]) and np.allclose(c[:, 0], 1), "G = B rising, R = 1")
mid = render_dt.dt_colours([np.sqrt(lo_dt * hi_dt)], lo_dt, hi_dt)[0]
expect(np.allclose(mid, (1, 0.5, 0.5), atol=0.01), f"geometric mean is half way (log scale), got {mid}")
for f in frames:
    img = mpimg.imread(tmp / "png" / (f.path.stem + ".png"))
    expect(img.shape[:2] == (H, W), f"{f.path.stem}.png is {W} x {H}, found {img.shape[1]} x {img.shape[0]}")
    rgb = img[..., :3]
    dt = f.point_data["dt"]
    if not (dt > 0).any():
        col, row = layout.to_pixel(f.points[0, 0], f.points[0, 1])
        expect(np.allclose(rgb[int(row), int(col)], 0.5, atol=0.03), f"{f.path.stem}: no dt yet -> grey, got {rgb[int(row), int(col)]}")
        continue
    # The particle with the smallest step is drawn on top, in the map's colour for its step.
    i = int(np.argmin(dt))
    col, row = layout.to_pixel(f.points[i, 0], f.points[i, 1])
    want = render_dt.dt_colours([dt[i]], lo_dt, hi_dt)[0]
    got = rgb[int(row), int(col)]
    expect(np.allclose(got, want, atol=0.03) and got[0] > 0.95 and got[1] < 0.6, f"{f.path.stem}: pixel at the smallest dt "
           f"particle {got} == {want} (red-ish)")
    if dt[i] == lo_dt:
        expect(np.allclose(got, (1, 0, 0), atol=0.03), f"{f.path.stem}: global smallest dt is pure red, got {got}")
    # Near-white particles exist in the dark plot area (largest steps are white).
    x0, y0 = layout.left, layout.top
    plot = rgb[y0 + 2:y0 + layout.plot_h - 2, x0 + 2:x0 + layout.plot_w - 2]
    expect(np.count_nonzero(np.all(plot > 0.93, axis=-1)) > 20, f"{f.path.stem}: white-ish (large dt) particles drawn")
    # Colour bar: red at the bottom, white at the top, G rising upwards.
    cx, cy, cw, ch = layout.cbar
    bar = rgb[cy + 2:cy + ch - 2, cx + cw // 2]
    expect(np.allclose(bar[-1], (1, 0, 0), atol=0.05) and np.allclose(bar[0], (1, 1, 1), atol=0.05),
           f"{f.path.stem}: colour bar red at bottom {bar[-1]}, white at top {bar[0]}")
    expect(np.all(np.diff(bar[::-1, 1]) >= -0.01), f"{f.path.stem}: colour bar G rises upwards")
for b in bad: print("  expected:", b)
sys.exit(1 if bad else 0)
EOF
check "PNG sizes; colour map red (smallest) .. white (largest), log; pixels at particles and colour bar" '[ $rc -eq 0 ]'

# 4. plot_dt.py: size, not blank, both runs drawn.
"$py" "$src/tools/plot_dt.py" "$tmp/glob" "$tmp/ind" --label global --label individual --out "$tmp/plot.png" \
  --width 700 --height 500 >"$tmp/plot.out" 2>&1; rc=$?
check "plot_dt.py exits 0 (got $rc: $(tail -1 "$tmp/plot.out"))" '[ $rc -eq 0 ]'
"$py" - "$tmp/plot.png" <<'EOF'; rc=$?
import sys
import numpy as np
import matplotlib.image as mpimg
img = mpimg.imread(sys.argv[1])[..., :3]
bad = []
if img.shape[:2] != (500, 700): bad.append(f"700 x 500 px, found {img.shape[1]} x {img.shape[0]}")
ink = np.count_nonzero(np.any(img < 0.9, axis=-1)) / (img.shape[0] * img.shape[1])
if ink < 0.02: bad.append(f"at least 2 % non-white pixels, found {100 * ink:.2f} %")
for name, hexc in (("global (C0)", "1f77b4"), ("individual (C1)", "ff7f0e")):
    want = np.array([int(hexc[k:k + 2], 16) / 255 for k in (0, 2, 4)])
    n = np.count_nonzero(np.all(np.abs(img - want) < 0.06, axis=-1))
    if n < 100: bad.append(f"{name} line drawn (>= 100 pixels of #{hexc}), found {n}")
for b in bad: print("  expected:", b)
sys.exit(1 if bad else 0)
EOF
check "plot_dt.png is 700 x 500, not blank, both runs' colours present" '[ $rc -eq 0 ]'
check "plot_dt.py names the clipped last step" 'grep -q "clipped to the end time" "$tmp/plot.out"'

# 5. Bad input: exit 2, the message names the file and what was expected.
"$py" "$src/tools/render_dt.py" "$tmp/glob/frames/frame_00000.vtu" --out "$tmp/png2" 2>"$tmp/err1"; rc=$?
check "frame without dt exits 2 (got $rc)" '[ $rc -eq 2 ]'
check "message names the frame, the missing dt and individual mode" \
  'grep -q "frame_00000.vtu: no point attribute \"dt\".*individual" "$tmp/err1"'
"$py" "$src/tools/render_dt.py" "$tmp/nope.vtu" 2>"$tmp/err2"; rc=$?
check "missing frame exits 2 naming it (got $rc)" '[ $rc -eq 2 ] && grep -q "nope.vtu: no such file" "$tmp/err2"'
head -c 300000 "$tmp/ind/frames/frame_00001.vtu" >"$tmp/cut.vtu"
"$py" "$src/tools/render_dt.py" "$tmp/cut.vtu" 2>"$tmp/err3"; rc=$?
check "truncated frame exits 2 (got $rc)" '[ $rc -eq 2 ] && grep -q "cut.vtu: .*truncated" "$tmp/err3"'
"$py" "$src/tools/plot_dt.py" "$tmp/missing_run" 2>"$tmp/err4"; rc=$?
check "missing stats.csv exits 2 naming it (got $rc)" '[ $rc -eq 2 ] && grep -q "missing_run: no such file or directory" "$tmp/err4"'
printf 'step,t,dt\n0,0,0.001\n' >"$tmp/old.csv"
"$py" "$src/tools/plot_dt.py" "$tmp/old.csv" 2>"$tmp/err5"; rc=$?
check "stats.csv without active_fraction exits 2 naming the column (got $rc)" \
  '[ $rc -eq 2 ] && grep -q "old.csv: missing column(s) active_fraction" "$tmp/err5"'

# A Python without numpy (here Debian's with its site packages off, -S): the tool says which
# Debian package to install, exit 2 (before: a ModuleNotFoundError traceback). Another
# interpreter first on PATH (pyenv, conda) instead runs the tool again with /usr/bin/python3.
/usr/bin/python3 -S "$src/tools/plot_dt.py" "$tmp/old.csv" 2>"$tmp/err6"; rc=$?
check "no numpy: exit 2 naming python3-numpy (got $rc)" \
  '[ $rc -eq 2 ] && grep -q "plot_dt.py: needs numpy, .*apt-get install python3-numpy" "$tmp/err6" && ! grep -q Traceback "$tmp/err6"'

# 6. mode_table.py and boundary_sweep.py when a run's output cannot be read or the tool dies
#    (tests/fake_sph_run.sh: the real sph-run, misbehaving for the runs its rules name): the
#    table is written after every run, a bad run is a marked row beside the complete others, the
#    tool exits 2 naming it; killed during a run, the table holds the runs before, complete.
fake="$src/tests/fake_sph_run.sh"
export FAKE_REAL="$run"
mt=("$py" "$src/tools/mode_table.py" "$src/scenes/martin_moyce.json" --scales 0.296296 --end 0.02 --sph-run "$fake")
"${mt[@]}" --extra foo --out "$tmp/mt0" 2>"$tmp/mt0.err"; rc=$?
check "mode_table --extra foo: exit 2 before any run (got $rc)" \
  '[ $rc -eq 2 ] && [ ! -e "$tmp/mt0" ] && grep -q "^mode_table.py: error: --extra '"'foo'"': no '"':'"' after the name; expected NAME:KEY=VALUE\[,KEY=VALUE...\]" "$tmp/mt0.err"'
"${mt[@]}" --extra "lv:simulation.stepping.lambda_v" --out "$tmp/mt0" 2>"$tmp/mt0.err"; rc=$?
check "mode_table --extra NAME:KEY (no =): exit 2 before any run (got $rc)" \
  '[ $rc -eq 2 ] && [ ! -e "$tmp/mt0" ] && grep -q "'"'simulation.stepping.lambda_v' is not KEY=VALUE"'" "$tmp/mt0.err"'
FAKE_RULES='*_individual:truncate-summary' "${mt[@]}" --extra "lv:simulation.stepping.mode=individual,simulation.stepping.lambda_v=0.1" \
  --out "$tmp/mt" >"$tmp/mt.out" 2>"$tmp/mt.err"; rc=$?
check "mode_table, individual's summary.json truncated: exit 2 naming it (got $rc)" \
  '[ $rc -eq 2 ] && ! grep -q Traceback "$tmp/mt.err" && grep -q "^mode_table.py: error: 1 run(s) not usable (scale 0.296296 individual: unreadable: .*_individual/summary.json: not valid JSON" "$tmp/mt.err"'
"$py" - "$tmp/mt" <<'EOF2'; rc=$?
import csv, pathlib, sys
d = pathlib.Path(sys.argv[1])
rows = {r["mode"]: r for r in csv.DictReader(open(d / "mode_table.csv"))}
bad = []
if list(rows) != ["constant", "global", "individual", "lv"]: bad.append(f"rows constant, global, individual, lv; found {list(rows)}")
for m in ("constant", "global", "lv"):
    r = rows.get(m, {})
    if r.get("status") != "ok" or r.get("particles") != "315" or not float(r.get("wall_s") or 0) > 0:
        bad.append(f"{m}: a complete row, found {r}")
r = rows.get("individual", {})
if not (r.get("status", "").startswith(f"unreadable: {d}/scale0.296296_individual/summary.json: not valid JSON") and r.get("runs") == "0"
        and r.get("wall_s") == ""):
    bad.append(f"individual: marked unreadable, no figures; found {r}")
if "| individual | unreadable: " not in (d / "mode_table.md").read_text(): bad.append("mode_table.md marks individual")
for b in bad: print("  expected:", b)
sys.exit(1 if bad else 0)
EOF2
check "mode_table.csv/.md: the unreadable run marked, the other three rows complete" '[ $rc -eq 0 ]'
# The accuracy and efficiency columns against a computation of their own: each row's RMS
# deviation from the constant run of the front probe and of the fluid probe's kinetic energy
# (numpy's interp of the row's series at the constant run's sample times), zero for the constant
# row itself; evaluations per particle = steps x average active fraction; S x f = the wall
# speed-up times it (the CSV's own figures, to 1e-9).
"$py" - "$tmp/mt" <<'EOF2'; rc=$?
import csv, json, math, pathlib, sys
import numpy as np
d = pathlib.Path(sys.argv[1])
rows = {r["mode"]: r for r in csv.DictReader(open(d / "mode_table.csv"))}
def series(mode, probe, column):
    c = np.genfromtxt(d / f"scale0.296296_{mode}" / "probes" / f"{probe}.csv", delimiter=",", names=True)
    return c["t"], c[column]
bad = []
for m in ("constant", "global", "lv"):
    r, s = rows[m], json.load(open(d / f"scale0.296296_{m}" / "summary.json"))
    for col, probe, column in (("rms_front_vs_constant_m", "front", "front"), ("rms_kinetic_vs_constant_J", "fluid", "kinetic")):
        t, v = series(m, probe, column)
        tr, vr = series("constant", probe, column)
        keep = tr <= t[-1] + 1e-12  # the reference's samples within the run
        want = float(np.sqrt(np.mean((np.interp(tr[keep], t, v) - vr[keep]) ** 2)))
        got = float(r[col])
        if m == "constant" and got != 0.0: bad.append(f"constant {col} 0, found {got}")
        if not math.isclose(got, want, rel_tol=1e-9, abs_tol=1e-15): bad.append(f"{m} {col} {want}, found {got}")
    if m != "constant" and not float(r["rms_kinetic_vs_constant_J"]) > 0: bad.append(f"{m}: a kinetic-energy deviation > 0")
    f = s["avg_active_fraction"]
    if not math.isclose(float(r["evaluations_per_particle"]), s["steps"] * f, rel_tol=1e-9): bad.append(f"{m} evaluations")
    if not math.isclose(float(r["speedup_times_active"]), float(r["speedup_vs_global"]) * f, rel_tol=1e-9): bad.append(f"{m} S x f")
if "| S × f | RMS dev front (mm) | RMS dev kinetic energy (J) |" not in (d / "mode_table.md").read_text(): bad.append("mode_table.md's columns")
for b in bad: print("  expected:", b)
sys.exit(1 if bad else 0)
EOF2
check "mode_table: RMS deviations from the constant run, evaluations per particle and S x f as computed apart" '[ $rc -eq 0 ]'
# --reuse takes a readable summary.json, but not one sph-run marked "interrupted" (nor the
# truncated one): those two runs again, the others reused; every row complete now, exit 0.
"$py" -c 'import json, sys
s = json.load(open(sys.argv[1])); s["interrupted"] = {"by": "SIGINT", "t": 0.01, "step": 9}
json.dump(s, open(sys.argv[1], "w"))' "$tmp/mt/scale0.296296_global/summary.json"
"${mt[@]}" --extra "lv:simulation.stepping.mode=individual,simulation.stepping.lambda_v=0.1" --reuse --out "$tmp/mt" \
  >"$tmp/mtr.out" 2>"$tmp/mtr.err"; rc=$?
check "mode_table --reuse: an interrupted summary.json is run again (got $rc)" \
  '[ $rc -eq 0 ] && grep -q "not reusing .*_global/summary.json: interrupted (SIGINT at t = 0.01 s); running it again" "$tmp/mtr.err" && grep -q "not reusing .*_individual/summary.json: unreadable: " "$tmp/mtr.err" && [ "$(grep -c "^reusing .*_\(constant\|lv\)/summary.json" "$tmp/mtr.err")" -eq 2 ] && ! grep -q interrupted "$tmp/mt/scale0.296296_global/summary.json" && [ "$(cut -d, -f2,21 "$tmp/mt/mode_table.csv" | tr -d "\r" | tr "\n" " ")" = "mode,status constant,ok global,ok individual,ok lv,ok " ]'
# --reuse takes a summary.json only of the run this invocation would make: another scene's
# (before: a table headed by one scene whose rows were another's), another end time or scale
# (0.2962961 shares the folder scale0.296296), another --extra value: each is named and run again.
ht=("$py" "$src/tools/mode_table.py" "$src/scenes/hydrostatic_tank.json" --scales 0.296296 --end 0.02 --sph-run "$run")
"${ht[@]}" --extra "lv:simulation.stepping.mode=individual,simulation.stepping.lambda_v=0.1" --reuse --out "$tmp/mt" \
  >"$tmp/mth.out" 2>"$tmp/mth.err"; rc=$?
check "mode_table --reuse, another scene's runs in --out: each named and run again (got $rc)" \
  '[ $rc -eq 0 ] && [ "$(grep -c "^not reusing $tmp/mt/scale0.296296_[a-z]*/summary.json: another run'"'"'s (scene '"'"'martin_moyce'"'"', expected '"'"'hydrostatic_tank'"'"'); running it again$" "$tmp/mth.err")" -eq 4 ] && ! grep -q "^reusing" "$tmp/mth.err" && [ "$(cut -d, -f1,2,21 "$tmp/mt/mode_table.csv" | tr -d "\r" | tr "\n" " ")" = "scene,mode,status hydrostatic_tank,constant,ok hydrostatic_tank,global,ok hydrostatic_tank,individual,ok hydrostatic_tank,lv,ok " ]'
"${ht[@]}" --extra "lv:simulation.stepping.mode=individual,simulation.stepping.lambda_v=0.2" --reuse --out "$tmp/mt" \
  >"$tmp/mth.out" 2>"$tmp/mth.err"; rc=$?
check "mode_table --reuse, --extra lv with another lambda_v: lv alone run again (got $rc)" \
  '[ $rc -eq 0 ] && [ "$(grep -c "^reusing " "$tmp/mth.err")" -eq 3 ] && grep -q "^not reusing .*_lv/summary.json: another run'"'"'s (simulation.stepping.lambda_v 0.1, expected 0.2); running it again$" "$tmp/mth.err" && grep -q "\"lambda_v\": 0.2" "$tmp/mt/scale0.296296_lv/scene_as_run.json"'
"$py" "$src/tools/mode_table.py" "$src/scenes/hydrostatic_tank.json" --scales 0.2962961 --end 0.03 --no-constant \
  --sph-run "$run" --reuse --out "$tmp/mt" >"$tmp/mth.out" 2>"$tmp/mth.err"; rc=$?
check "mode_table --reuse, another end time and scale: run again, both named (got $rc)" \
  '[ $rc -eq 0 ] && grep -q "^not reusing .*_global/summary.json: another run'"'"'s (simulation.end_time 0.02, expected 0.03; simulation.scale 0.296296, expected 0.2962961); running it again$" "$tmp/mth.err" && [ "$(grep -c "^not reusing" "$tmp/mth.err")" -eq 2 ]'
# A scene file edited since its runs, under the same name: --reuse runs them again, saying why.
cp "$src/scenes/hydrostatic_tank.json" "$tmp/tank.json"
et=("$py" "$src/tools/mode_table.py" "$tmp/tank.json" --scales 0.296296 --end 0.02 --no-constant --sph-run "$run" --out "$tmp/mte")
"${et[@]}" >/dev/null 2>&1; sed -i 's/"viscosity": *[0-9.e-]*/"viscosity": 0.2/' "$tmp/tank.json"
"${et[@]}" --reuse >/dev/null 2>"$tmp/mte.err"; rc=$?
check "mode_table --reuse, the scene file edited since: each run named and run again (got $rc)" \
  '[ $rc -eq 0 ] && [ "$(grep -c "^not reusing .*summary.json: another run.s (the scene file has changed since (its SHA-256 differs)); running it again$" "$tmp/mte.err")" -eq 2 ] && grep -q "\"viscosity\": 0.2" "$tmp/mte/scale0.296296_global/scene_as_run.json"'
# --set applies to every configuration, an --extra's own value of the same key winning; --reuse
# then takes every run (the key set twice is checked at its last value); a --set that is not
# KEY=VALUE is refused before any run.
st=("$py" "$src/tools/mode_table.py" "$src/scenes/hydrostatic_tank.json" --scales 0.296296 --end 0.02 --no-constant
    --sph-run "$run" --out "$tmp/mts" --set simulation.stepping.lambda_c=0.7 --extra "lc:simulation.stepping.mode=global,simulation.stepping.lambda_c=0.5")
"${st[@]}" >/dev/null 2>&1; rc=$?
"${st[@]}" --reuse >/dev/null 2>"$tmp/mts.err"; rc2=$?
lc() { "$py" -c 'import json, sys; print(json.load(open(sys.argv[1]))["simulation"]["stepping"]["lambda_c"])' "$tmp/mts/scale0.296296_$1/scene_as_run.json"; }
check "mode_table --set: lambda_c 0.7 in global and individual, the extra's own 0.5 in lc ($(lc global) $(lc individual) $(lc lc)); --reuse takes all three (got $rc, $rc2)" \
  '[ $rc -eq 0 ] && [ $rc2 -eq 0 ] && [ "$(lc global) $(lc individual) $(lc lc)" = "0.7 0.7 0.5" ] && [ "$(grep -c "^reusing " "$tmp/mts.err")" -eq 3 ]'
"$py" "$src/tools/mode_table.py" "$src/scenes/hydrostatic_tank.json" --set lambda_c --out "$tmp/mt0" 2>"$tmp/mt0.err"; rc=$?
check "mode_table --set lambda_c (no =): exit 2 before any run (got $rc)" \
  '[ $rc -eq 2 ] && [ ! -e "$tmp/mt0" ] && grep -q "^mode_table.py: error: --set '"'lambda_c'"': not KEY=VALUE" "$tmp/mt0.err"'
# Ctrl-C at a terminal (SIGINT to the tool's whole process group, which the fake sends during
# the individual run): the run gets exactly one signal, the tool's SIGTERM, and saves its
# summary marked "interrupted" by it; the tool dies by SIGINT, the table keeps the first two rows.
FAKE_RULES='*_individual:int-group' setsid --wait "${mt[@]}" --out "$tmp/mti" >/dev/null 2>"$tmp/mti.err"; rc=$?
check "mode_table, Ctrl-C to its process group (got $rc): one SIGTERM reaches the run ($(cat "$tmp/mti/scale0.296296_individual/fake_signals" 2>/dev/null)), which saves its summary" \
  '[ $rc -eq 130 ] && [ "$(cat "$tmp/mti/scale0.296296_individual/fake_signals")" = TERM ] && grep -q "\"by\": \"SIGTERM\"" "$tmp/mti/scale0.296296_individual/summary.json" && grep -q "^mode_table.py: interrupted$" "$tmp/mti.err" && [ "$(cut -d, -f2,21 "$tmp/mti/mode_table.csv" | tr -d "\r" | tr "\n" " ")" = "mode,status constant,ok global,ok " ]'
FAKE_RULES='*_individual:kill-tool' "${mt[@]}" --out "$tmp/mtk" >/dev/null 2>&1; rc=$?
check "mode_table killed at its third run (got $rc): the table has the first two, complete" \
  '[ $rc -eq 137 ] && [ "$(cut -d, -f2,21 "$tmp/mtk/mode_table.csv" | tr -d "\r" | tr "\n" " ")" = "mode,status constant,ok global,ok " ]'
# The global run fails: a row "failed (exit 3)", constant (whose step is global's smallest)
# skipped with the reason, individual complete; exit 2 naming the failed run.
FAKE_RULES='*_global:fail' "${mt[@]}" --out "$tmp/mtf" >/dev/null 2>"$tmp/mtf.err"; rc=$?
"$py" - "$tmp/mtf/mode_table.csv" <<'EOF'; rows=$?
import csv, sys
rows = [(r["mode"], r["runs"], r["status"]) for r in csv.DictReader(open(sys.argv[1]))]
want = [("constant", "0", "skipped: its step is the first global run's smallest, and that run is not usable"),
        ("global", "0", "failed (exit 3)"), ("individual", "1", "ok")]
if rows != want: print("  expected:", want, "found", rows)
sys.exit(rows != want)
EOF
check "mode_table, global failed: a failed row, constant skipped, individual complete, exit 2 (got $rc)" \
  '[ $rc -eq 2 ] && [ $rows -eq 0 ] && grep -q "^mode_table.py: error: 1 run(s) not usable (scale 0.296296 global: failed (exit 3))" "$tmp/mtf.err" && grep -q "^| global | failed (exit 3) |" "$tmp/mtf/mode_table.md"'
# --extra names that share a run folder once spaces become _ are refused before any run.
"${mt[@]}" --extra "a b:simulation.stepping.lambda_v=0.1" --extra "a_b:simulation.stepping.lambda_v=0.2" --out "$tmp/mt0" 2>"$tmp/mt0.err"; rc=$?
check "mode_table --extra 'a b' and 'a_b': exit 2 naming both (got $rc)" \
  '[ $rc -eq 2 ] && [ ! -e "$tmp/mt0" ] && grep -q "^mode_table.py: error: --extra '"'a_b:.*'"': the name '"'a_b'"' and '"'a b'"' share the run folder" "$tmp/mt0.err"'
bs=("$py" "$src/tools/boundary_sweep.py" --scene "$src/scenes/corner_breaking_dam.json" --scale 0.1 --end 0.01
    --dts 0.001,0.002 --sph-run "$fake")
FAKE_RULES='*/ihmsen_0.002/run:truncate-probes' "${bs[@]}" --out "$tmp/bs" >"$tmp/bs.out" 2>"$tmp/bs.err"; rc=$?
check "boundary_sweep, a probe file cut mid-row: exit 2 naming it (got $rc)" \
  '[ $rc -eq 2 ] && ! grep -q Traceback "$tmp/bs.err" && grep -q "^boundary_sweep.py: error: 1 run(s) not usable (ihmsen Δt 0.002: unreadable: .*ihmsen_0.002/run/probes/fluid.csv: line 6: cut short" "$tmp/bs.err"'
check "boundary_sweep.md: that row marked, the other three completed" \
  '[ "$(grep -c "| completed |" "$tmp/bs/boundary_sweep.md")" -eq 3 ] && grep -q "^| ihmsen | 0.002 | unreadable: .*fluid.csv: line 6: " "$tmp/bs/boundary_sweep.md" && grep -q "ihmsen: whole fluid 0.001, interior 0.001 (a run was unreadable or interrupted: a lower bound)" "$tmp/bs/boundary_sweep.md"'
FAKE_RULES='*/direct_forcing_0.001/run:kill-tool' "${bs[@]}" --out "$tmp/bsk" >/dev/null 2>&1; rc=$?
check "boundary_sweep killed at its third run (got $rc): boundary_sweep.md has the first two rows" \
  '[ $rc -eq 137 ] && [ "$(grep -c "^| ihmsen | 0.00[12] | completed |" "$tmp/bsk/boundary_sweep.md")" -eq 2 ] && ! grep -q "^| direct_forcing" "$tmp/bsk/boundary_sweep.md"'

# 7. sph_python's shared pieces on their own: write_atomic interrupted at its rename leaves the
#    old table and no temporary, and removes a temporary an earlier (killed) writer left; a CSV
#    whose last line has no newline (cut short at a cell boundary) is unreadable; Markdown cells
#    escape |; a run is classified failed / interrupted / unreadable / usable; Ctrl-C and SIGTERM
#    end a tool by that signal after ending and waiting for its child; a CSV error exits 2.
"$py" - "$tmp/unit" <<'EOF'; rc=$?
import os, pathlib, signal, subprocess, sys
import sph_python as sp
d = pathlib.Path(sys.argv[1]); d.mkdir()
bad = []
def expect(cond, what):
    if not cond: bad.append(what)
t = d / "t.md"
t.write_text("old\n")
(d / ".t.md.tmp1").write_text("left by a killed writer")
real = os.replace
def interrupted(*a): raise KeyboardInterrupt
os.replace = interrupted
try:
    sp.write_atomic(t, "new\n")
    bad.append("write_atomic: the KeyboardInterrupt of os.replace goes on")
except KeyboardInterrupt:
    pass
finally:
    os.replace = real
expect(t.read_text() == "old\n", f"the old table intact after an interrupted write, found {t.read_text()!r}")
expect(sorted(p.name for p in d.iterdir()) == ["t.md"], f"no temporary left, found {sorted(p.name for p in d.iterdir())}")
sp.write_atomic(t, "new\n")
expect(t.read_text() == "new\n", "write_atomic writes")
c = d / "cut.csv"
c.write_text("t,x\n0,1\n0.1,2")  # cut after a whole cell: every row has its two numbers
try:
    sp.read_csv_columns(c)
    bad.append("a CSV without its final newline is Unreadable")
except sp.Unreadable as e:
    expect(str(e) == f"{c}: line 3: cut short (the file ends inside it, without a newline)", f"message: {e}")
expect(sp.read_csv_columns(c, final_newline=False) == {"t": [0.0, 0.1], "x": [1.0, 2.0]}, "final_newline=False reads it")
expect(sp.md_cell("a|b") == "a\\|b" and sp.md_status_row("x|y", "failed (exit 3)", 4) == "| x\\|y | failed (exit 3) | | |",
       f"Markdown escaping: {sp.md_status_row('x|y', 'failed (exit 3)', 4)!r}")
r = d / "run"; r.mkdir()
(r / "summary.json").write_text('{"steps": 9, "interrupted": {"by": "SIGTERM", "t": 0.5, "step": 9}}\n')
expect(sp.read_run(r, 143) == (None, "interrupted (SIGTERM at t = 0.5 s)"), f"exit 143: {sp.read_run(r, 143)}")
expect(sp.read_run(r, 0) == (None, "interrupted (SIGTERM at t = 0.5 s)"), f"exit 0, marked: {sp.read_run(r, 0)}")
expect(sp.read_run(r, 3) == (None, "failed (exit 3)"), f"exit 3: {sp.read_run(r, 3)}")
(r / "summary.json").write_text('{"steps": 9}\n')
expect(sp.read_run(r, 0, numbers=("steps",)) == ({"steps": 9}, None), "a usable run")
expect(sp.read_run(r, 0, numbers=("wall_time_s",))[1] == f'unreadable: {r}/summary.json: no "wall_time_s"', "unreadable")
# An earlier run read with rc 0 (--reuse) that sph-run marked failed or saved from its reserve.
(r / "summary.json").write_text('{"steps": 9, "failed": {"reason": "NaN", "t": 0.1, "step": 9}}\n')
expect(sp.read_run(r, 0) == (None, "failed (exit 3)"), f"exit 0, marked failed: {sp.read_run(r, 0)}")
(r / "summary.json").write_text('{"steps": 9, "output_failed": {"reason": "disk full", "t": 0.1, "step": 9}}\n')
expect(sp.read_run(r, 0) == (None, "failed (exit 5)"), f"exit 0, marked output_failed: {sp.read_run(r, 0)}")
# A tool (errors_as_exit_2) stopped while its child runs: the child ended and waited for, the
# tool dead by the signal (the shell's 130 / 143), one line.
tool = ("import os, signal, sys, threading\nimport sph_python as sp\nsp.errors_as_exit_2()\n"
        "threading.Timer(0.5, os.kill, (os.getpid(), getattr(signal, sys.argv[2]))).start()\n"
        "sp.run_child(['bash', '-c', 'echo $$ > ' + sys.argv[1] + '; exec sleep 30'], os.devnull)\n")
for sig, line in (("SIGINT", "-c: interrupted"), ("SIGTERM", "-c: interrupted (SIGTERM)")):
    p = subprocess.run([sys.executable, "-c", tool, str(d / "child.pid"), sig], capture_output=True, text=True)
    expect(p.returncode == -getattr(signal, sig) and p.stderr.strip().endswith(line),
           f"{sig}: died by it with '{line}', found {p.returncode}, {p.stderr.strip()!r}")
    pid = int((d / "child.pid").read_text())
    try:
        os.kill(pid, 0)
        bad.append(f"{sig}: the tool's child {pid} ended")
    except ProcessLookupError:
        pass
p = subprocess.run([sys.executable, "-c", "import csv, sys, sph_python as sp\nsp.errors_as_exit_2()\n"
                    "raise csv.Error('bad quoting')"], capture_output=True, text=True)
expect(p.returncode == 2 and p.stderr == "-c: error: an input file is not valid CSV: bad quoting\n",
       f"csv.Error: exit 2, one line; found {p.returncode} {p.stderr!r}")
for b in bad: print("  expected:", b)
sys.exit(1 if bad else 0)
EOF
check "sph_python: write_atomic interrupted, a CSV cut short, Markdown cells, runs classified, tools ended by Ctrl-C/SIGTERM" '[ $rc -eq 0 ]'

# pcisph_table.py --reuse keeps a run only if its pcisph_table.json records this very command:
# the same again is reused; another --end is run again, saying why (it reused any summary.json).
pt=("$py" "$src/tools/pcisph_table.py" "$src/scenes/shock.json" --scale 0.5 --no-constant --sph-run "$run" --out "$tmp/pt")
"${pt[@]}" --end 0.005 >/dev/null 2>&1 && "${pt[@]}" --end 0.005 --reuse >/dev/null 2>"$tmp/pt_same"; rc=$?
"${pt[@]}" --end 0.008 --reuse >/dev/null 2>"$tmp/pt_other"; rc2=$?
check "pcisph_table --reuse: the same command reused, another --end run again (got $rc, $rc2)" \
  '[ $rc -eq 0 ] && [ $rc2 -eq 0 ] && grep -q "^reusing .*shock_adaptive" "$tmp/pt_same" && grep -q "not reusing .*shock_adaptive/summary.json: another scene or other options; running it again" "$tmp/pt_other" && [ "$(python3 -c "import json; print(json.load(open(\"$tmp/pt/shock_adaptive/scene_as_run.json\"))[\"simulation\"][\"end_time\"])")" = 0.008 ]'

[ $fail -eq 0 ] && echo "tools plots: all checks passed"
exit $fail
