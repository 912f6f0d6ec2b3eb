#!/usr/bin/env python3
"""He et al. Table 1 for one scene: `constant`, `global` and `individual` stepping side by side,
at one or more sizes, run one after another (never in parallel) so the wall times compare.

usage: tools/mode_table.py SCENE.json [--scales 1,2] [--end T] [--threads 2]
                           [--sph-run build/tools/sph-run] [--out out/mode_table]
                           [--extra NAME:KEY=VALUE,KEY=VALUE ...]

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
import sys
import time

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("scene")
ap.add_argument("--scales", default="1")
ap.add_argument("--end", type=float, default=None, help="simulated seconds (default: the scene's end_time)")
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--no-constant", action="store_true", help="skip the constant-step run (it is the slowest)")
ap.add_argument("--sph-run", default="build/tools/sph-run")
ap.add_argument("--out", default="out/mode_table")
ap.add_argument("--extra", action="append", default=[],
                help="an extra configuration, e.g. 'individual(global λ):simulation.stepping.mode=individual,"
                     "simulation.stepping.lambda_v=0.1'")
args = ap.parse_args()

if not pathlib.Path(args.sph_run).exists():
    sys.exit(f"{args.sph_run}: not found (build first: cmake --build build)")
out_root = pathlib.Path(args.out)


def run(tag, scale, sets):
    out = out_root / f"scale{scale:g}_{tag.replace(' ', '_').replace('(', '').replace(')', '')}"
    cmd = [args.sph_run, args.scene, "--scale", str(scale), "--threads", str(args.threads), "--no-frames", "-q",
           "--out", str(out)]
    if args.end is not None:
        cmd += ["--end", str(args.end)]
    for s in sets:
        cmd += ["--set", s]
    print(f"[{time.strftime('%H:%M:%S')}] {' '.join(cmd)}", file=sys.stderr, flush=True)
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"run failed (exit {proc.returncode}): {' '.join(cmd)}\n{proc.stderr.strip()}")
    return json.loads((out / "summary.json").read_text())


rows = []
for scale in [float(s) for s in args.scales.split(",")]:
    g = run("global", scale, ["simulation.stepping.mode=global"])
    c = None if args.no_constant else run(
        "constant", scale, ["simulation.stepping.mode=constant", f"simulation.stepping.dt={g['min_dt_s']!r}"])
    i = run("individual", scale, ["simulation.stepping.mode=individual"])
    size_rows = ([("constant", c)] if c else []) + [("global", g), ("individual", i)]
    for spec in args.extra:
        name, _, sets = spec.partition(":")
        size_rows.append((name, run(name, scale, [s for s in sets.split(",") if s])))
    for name, s in size_rows:
        rows.append({
            "scene": s["scene"], "mode": name, "particles": s["fluid_particles"],
            "simulated_s": s["simulated_time_s"], "wall_s": s["wall_time_s"], "steps": s["steps"],
            "avg_dt_ms": 1e3 * s["avg_dt_s"], "min_dt_ms": 1e3 * s["min_dt_s"], "max_dt_ms": 1e3 * s["max_dt_s"],
            "avg_active_pct": 100 * s["avg_active_fraction"], "max_density_error_pct": 100 * s["max_density_error"],
            "front_x_m": s.get("front_x_m", float("nan")), "collisions": s["boundary_collisions_total"],
            "speedup_vs_global": g["wall_time_s"] / s["wall_time_s"],
            "speedup_vs_constant": c["wall_time_s"] / s["wall_time_s"] if c else float("nan"),
        })

machine = f"{os.cpu_count()} cores, {platform.processor() or platform.machine()}"
lines = [f"`{pathlib.Path(args.scene).name}`, {args.threads} threads, {machine}, "
         f"{time.strftime('%Y-%m-%d')}; runs one after another, no frames written.", "",
         "| mode | particles | simulated s | wall s | steps | avg Δt_sim ms (min–max) | avg active | "
         "max ρ error | front x m | net catches | speed-up vs global (vs constant) |",
         "|---|---|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    lines.append(f"| {r['mode']} | {r['particles']:,} | {r['simulated_s']:.2f} | {r['wall_s']:.1f} | {r['steps']:,} | "
                 f"{r['avg_dt_ms']:.3f} ({r['min_dt_ms']:.3f}–{r['max_dt_ms']:.3f}) | {r['avg_active_pct']:.0f} % | "
                 f"{r['max_density_error_pct']:.1f} % | {r['front_x_m']:.3f} | {r['collisions']} | "
                 f"{r['speedup_vs_global']:.2f} ({r['speedup_vs_constant']:.2f}) |")
text = "\n".join(lines) + "\n"
print(text)
out_root.mkdir(parents=True, exist_ok=True)
(out_root / "mode_table.md").write_text(text)
with open(out_root / "mode_table.csv", "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
    w.writeheader()
    w.writerows(rows)
