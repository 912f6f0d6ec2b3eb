#!/usr/bin/env bash
# sph-study end to end on a tiny Martin & Moyce run (512 particles, 0.06 s): every mode the
# scene loads with becomes a row (WCSPH constant/global/individual/binned, PCISPH and DFSPH constant/adaptive), the constant row steps at the global run's smallest step,
# the reference run exists and the tables, the Pareto plot and the dt plot are written; the
# experiment column is filled; the Pareto front of known points is the non-dominated set.
# usage: sph_study.sh BUILD_TOOLS_DIR SOURCE_DIR
set -euo pipefail
tools=$1; src=$2
out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
cd "$src"
"$tools/sph-study" scenes/martin_moyce.json --scale 0.296296 --end 0.06 --out "$out/s" \
    --config "individual --set stepping.lambda_v=0.1 --name ind-0.1" > "$out/log" 2>&1 || { cat "$out/log"; exit 1; }
grep -q "run 1/10" "$out/log"  # the reference and nine configurations
/usr/bin/python3 - "$out/s" "$tools" <<'PY'
import csv, json, pathlib, sys, importlib.machinery
d = pathlib.Path(sys.argv[1])
rows = list(csv.DictReader(open(d / "study.csv")))
assert [r["configuration"] for r in rows] == ["constant", "global", "individual", "binned", "pcisph/constant",
                                              "pcisph/adaptive", "dfsph/constant", "dfsph/adaptive", "ind-0.1"], rows
assert all(r["status"] == "ok" for r in rows)
def first_dt(run):  # the step of a constant run (its last step may be clipped to the end)
    return float(next(csv.DictReader(open(run / "stats.csv")))["dt"])
g = json.loads(next(p for p in d.iterdir() if p.name.endswith("_global")).joinpath("summary.json").read_text())
c = next(p for p in d.iterdir() if p.name.split("_", 1)[-1] == "constant")  # not pcisph_constant
assert abs(first_dt(c) - g["min_dt_s"]) < 2e-12, (first_dt(c), g["min_dt_s"])    # whole ticks of 1 ps
assert abs(first_dt(d / "reference") - 0.5 * g["min_dt_s"]) < 2e-12
for r in rows:
    assert float(r["speedup_vs_global"]) > 0 and float(r["deviation (mean rel.)"]) >= 0
    assert "exp err front %" in r and float(r["exp err front %"]) > 0
    assert float(r["cpu_s"]) > 0
assert float(next(r for r in rows if r["configuration"] == "global")["speedup_vs_global"]) == 1.0
md = (d / "study.md").read_text()
assert md.count("\n| ") == 10 and "exp. err front" in md and "2 threads" in md, md
for png in ("pareto.png", "dt.png"):
    b = (d / png).read_bytes()
    assert b[:8] == b"\x89PNG\r\n\x1a\n" and len(b) > 10000, png
study = importlib.machinery.SourceFileLoader("study", sys.argv[2] + "/sph-study").load_module()
pts = [(1, 5), (2, 3), (3, 4), (4, 1), (5, 1), (float("nan"), 0)]
assert study.pareto_front(pts) == [0, 1, 3], study.pareto_front(pts)
print("sph-study: ok")
PY
