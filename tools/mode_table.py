#!/usr/bin/env python3
"""He et al. Table 1 for one scene: `constant`, `global` and `individual` stepping side by side,
at one or more sizes, run one after another (never in parallel) so the wall times compare.

usage: tools/mode_table.py SCENE.json [--scales 1,2] [--end T] [--threads 2] [--repeat 3]
                           [--sph-run build/tools/sph-run] [--out out/mode_table]
                           [--extra NAME:KEY=VALUE,KEY=VALUE ...]

With --repeat K every configuration runs K times, interleaved round by round (global,
individual, ..., then again), and the table gives the median wall and CPU time, so a burst
of load from other processes hits one round of every mode instead of one mode. The runs
are deterministic (same steps and results each time); only the times vary.

The `constant` run uses the smallest step the `global` run of the same size took (its
`min_dt_s`), i.e. the largest fixed step known to be stable for the whole run, which is how
a user without adaptivity would have to choose it. Each run's outputs stay in --out/<size>_<mode>/.
Prints a Markdown table and writes mode_table.md and mode_table.csv into --out.
"""
import argparse
import csv
import json
import os
import pathlib
import platform
import subprocess
import statistics
import sys
import time
from sph_python import errors_as_exit_2, positive_list, require  # noqa: E402 (tools/ is the script's folder)

errors_as_exit_2()

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("scene")
ap.add_argument("--scales", default="1")
ap.add_argument("--end", type=float, default=None, help="simulated seconds (default: the scene's end_time)")
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--no-constant", action="store_true", help="skip the constant-step run (it is the slowest)")
ap.add_argument("--repeat", type=int, default=1, help="runs per configuration, interleaved; medians reported")
ap.add_argument("--sph-run", default="build/tools/sph-run")
ap.add_argument("--out", default="out/mode_table")
ap.add_argument("--reuse", action="store_true",
                help="read a run's summary.json from --out if it is there instead of running it again "
                     "(re-tabulates an earlier or interrupted table with the same options)")
ap.add_argument("--extra", action="append", default=[],
                help="an extra configuration, e.g. 'individual(global λ):simulation.stepping.mode=individual,"
                     "simulation.stepping.lambda_v=0.1'")
args = ap.parse_args()
SCALES = positive_list(args.scales, "--scales")
require(args.repeat >= 1, f"--repeat {args.repeat}: expected at least 1")

if not pathlib.Path(args.sph_run).exists():
    sys.exit(f"{args.sph_run}: not found (build first: cmake --build build)")
out_root = pathlib.Path(args.out)


def run(tag, scale, sets, rep=0):
    name = tag.replace(' ', '_').replace('(', '').replace(')', '')
    out = out_root / f"scale{scale:g}_{name}" / f"run{rep}" if args.repeat > 1 else out_root / f"scale{scale:g}_{name}"
    cmd = [args.sph_run, args.scene, "--scale", str(scale), "--threads", str(args.threads), "--no-frames", "-q",
           "--out", str(out)]
    if args.end is not None:
        cmd += ["--end", str(args.end)]
    for s in sets:
        cmd += ["--set", s]
    if args.reuse and (out / "summary.json").exists():
        print(f"reusing {out / 'summary.json'}", file=sys.stderr, flush=True)
        return json.loads((out / "summary.json").read_text())
    print(f"[{time.strftime('%H:%M:%S')}] {' '.join(cmd)}", file=sys.stderr, flush=True)
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"run failed (exit {proc.returncode}): {' '.join(cmd)}\n{proc.stderr.strip()}")
    return json.loads((out / "summary.json").read_text())


def fronts(s):
    return [f["x"] for f in s.get("front_x_m_at", [])]


rows = []
system_tables = []  # per scale: (configurations, {system: {configuration: ms per step}})
for scale in SCALES:
    # The first global run also fixes the constant step (its smallest step).
    first = run("global", scale, ["simulation.stepping.mode=global"], 0)
    configs = [("global", ["simulation.stepping.mode=global"])]
    if not args.no_constant:
        configs.append(("constant", ["simulation.stepping.mode=constant", f"simulation.stepping.dt={first['min_dt_s']!r}"]))
    configs.append(("individual", ["simulation.stepping.mode=individual"]))
    for spec in args.extra:
        name, _, sets = spec.partition(":")
        configs.append((name, [s for s in sets.split(",") if s]))
    runs = {name: [] for name, _ in configs}
    runs["global"].append(first)
    for rep in range(args.repeat):
        for name, sets in configs:
            if name == "global" and rep == 0:
                continue
            runs[name].append(run(name, scale, sets, rep))
    med = {name: (statistics.median(r["wall_time_s"] for r in rs), statistics.median(r.get("cpu_time_s", float("nan")) for r in rs))
           for name, rs in runs.items()}
    g = runs["global"][0]
    per_step = {}
    for name, rs in runs.items():
        for r in rs:
            for sy in r.get("systems", []):
                per_step.setdefault(sy["name"], {}).setdefault(name, []).append(1e3 * sy["seconds"] / max(r["steps"], 1))
    extras = [n for n, _ in configs if n not in ("global", "constant", "individual")]
    order = (["constant"] if "constant" in runs else []) + ["global", "individual"] + extras
    for name in order:
        s = runs[name][0]
        wall, cpu = med[name]
        gf, sf = fronts(g), fronts(s)
        dev = max((abs(a - b) / abs(b) for a, b in zip(sf, gf) if b), default=float("nan"))
        rows.append({
            "scene": s["scene"], "mode": name, "particles": s["fluid_particles"],
            "simulated_s": s["simulated_time_s"], "runs": len(runs[name]), "wall_s": wall, "cpu_s": cpu, "steps": s["steps"],
            "avg_dt_ms": 1e3 * s["avg_dt_s"], "min_dt_ms": 1e3 * s["min_dt_s"], "max_dt_ms": 1e3 * s["max_dt_s"],
            "avg_active_pct": 100 * s["avg_active_fraction"], "max_density_error_pct": 100 * s["max_density_error"],
            "front_t_s": " ".join(f"{f['t']:.2f}" for f in s.get("front_x_m_at", [])),
            "front_x_m": " ".join(f"{x:.3f}" for x in sf), "front_dev_vs_global_pct": 100 * dev,
            "collisions": s["boundary_collisions_total"],
            "speedup_vs_global": med["global"][0] / wall,
            "speedup_vs_global_cpu": med["global"][1] / cpu,
            "speedup_vs_constant": med["constant"][0] / wall if "constant" in med else float("nan"),
        })
    system_tables.append((scale, order, {sy: {n: statistics.median(v) for n, v in c.items()} for sy, c in per_step.items()}))

machine = f"{os.cpu_count()} cores, {platform.processor() or platform.machine()}"
lines = [f"`{pathlib.Path(args.scene).name}`, {args.threads} threads, {machine}, "
         f"{time.strftime('%Y-%m-%d')}; runs one after another, no frames written; "
         f"{args.repeat} run(s) per configuration, interleaved, median times; front deviation is the largest "
         f"|x - x_global| / x_global over the three times.", "",
         "| mode | particles | simulated s | wall s | CPU s | steps | avg Δt_sim ms (min–max) | avg active | "
         "max ρ error | front x m at t s | front vs global | net catches | speed-up vs global: wall, CPU (wall vs constant) |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    lines.append(f"| {r['mode']} | {r['particles']:,} | {r['simulated_s']:.2f} | {r['wall_s']:.1f} | {r['cpu_s']:.1f} | {r['steps']:,} | "
                 f"{r['avg_dt_ms']:.3f} ({r['min_dt_ms']:.3f}–{r['max_dt_ms']:.3f}) | {r['avg_active_pct']:.0f} % | "
                 f"{r['max_density_error_pct']:.1f} % | {r['front_x_m']} at {r['front_t_s']} | {r['front_dev_vs_global_pct']:.1f} % | {r['collisions']} | "
                 f"{r['speedup_vs_global']:.2f}, {r['speedup_vs_global_cpu']:.2f} ({r['speedup_vs_constant']:.2f}) |")
# Where a step's time goes: each system's wall time per step from summary.json (median over the
# runs of a configuration); a system a configuration does not build shows a dash.
for scale, order, table in system_tables:
    lines += ["", f"Milliseconds per step by system (scale {scale:g}; median over the runs; `step` is their sum):", "",
              "| system | " + " | ".join(order) + " |", "|---|" + "---|" * len(order)]
    for sy, by in table.items():
        lines.append(f"| {sy} | " + " | ".join(f"{by[n]:.2f}" if n in by else "–" for n in order) + " |")
    lines.append("| **step** | " + " | ".join(f"**{sum(by.get(n, 0.0) for by in table.values()):.2f}**" for n in order) + " |")
text = "\n".join(lines) + "\n"
print(text)
out_root.mkdir(parents=True, exist_ok=True)
(out_root / "mode_table.md").write_text(text)
with open(out_root / "mode_table.csv", "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
    w.writeheader()
    w.writerows(rows)
