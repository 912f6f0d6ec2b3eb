#!/usr/bin/python3
"""Ihmsen et al. 2010 sec. 4.1: the largest constant step that keeps the overall volume
compression below 1 % (max over time of rho_err_avg < eta) with three PCISPH iterations, for
the boundary of sec. 3.2 (`ihmsen`) and for `direct_forcing` alone. The paper found
0.0045 s against 0.0008 s on a 23k corner breaking dam.

usage: tools/boundary_sweep.py [--scene scenes/corner_breaking_dam.json] [--scale 1.2] [--end 0.6]
                               [--dts 0.0008,0.0015,0.0025,0.0035,0.0045] [--threads 2] [--out out/boundary_sweep]

Runs one at a time, in increasing dt, and stops a handling once a step fails on both measures
(compression >= 1 % or a simulation error): the paper's whole-fluid average, and the same
average over the interior fluid (no boundary particle within h; a fluid probe sampled every
step), which leaves out the wall layer where the handlings differ in what they count.
Prints a Markdown table; writes boundary_sweep.md.
"""
import argparse
import csv
import json
import pathlib
import statistics
import subprocess
import sys
import time
from sph_python import errors_as_exit_2, positive_list, require  # noqa: E402 (tools/ is the script's folder)

errors_as_exit_2()

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--scene", default="scenes/corner_breaking_dam.json")
ap.add_argument("--scale", type=float, default=1.2)
ap.add_argument("--end", type=float, default=0.6)
ap.add_argument("--dts", default="0.0008,0.0015,0.0025,0.0035,0.0045")
ap.add_argument("--eta", type=float, default=0.01)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--sph-run", default="build/tools/sph-run")
ap.add_argument("--out", default="out/boundary_sweep")
args = ap.parse_args()
DTS = positive_list(args.dts, "--dts")
require(args.eta > 0, f"--eta {args.eta}: expected a fraction > 0")
out_root = pathlib.Path(args.out)
out_root.mkdir(parents=True, exist_ok=True)
rows = []
best = {}        # handling -> largest dt passing on the whole-fluid average (the paper's measure)
best_inner = {}  # handling -> largest dt passing on the interior average (no wall within h)
scene = json.loads(pathlib.Path(args.scene).read_text())
for handling in ("ihmsen", "direct_forcing"):
    failed_whole = failed_inner = False
    for dt in DTS:
        out = out_root / f"{handling}_{dt:g}"
        out.mkdir(parents=True, exist_ok=True)
        # The scene with a fluid probe sampled every step (engine/run/probes.hpp: whole-fluid and
        # interior density errors). Written next to the outputs; the scene has no relative files.
        probed = dict(scene)
        probed["probes"] = [{"type": "fluid", "name": "fluid", "rate": 1.0 / dt}]
        scene_file = out / "scene.json"
        scene_file.write_text(json.dumps(probed, indent=1))
        cmd = [args.sph_run, str(scene_file), "--scale", str(args.scale), "--end", str(args.end), "--threads",
               str(args.threads), "--no-frames", "-q", "--out", str(out / "run"), "--mode", "constant", "--dt", repr(dt),
               "--set", f"boundary.handling={handling}", "--set", "pcisph.iterations=3", "--set", "pcisph.loop=fixed"]
        print(f"[{time.strftime('%H:%M:%S')}] {' '.join(cmd)}", file=sys.stderr, flush=True)
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode == 0:
            s = json.loads((out / "run" / "summary.json").read_text())
            err, err_max, status = s["max_avg_density_error"], s["max_density_error"], "completed"
            with open(out / "run" / "probes" / "fluid.csv") as f:
                probe = list(csv.DictReader(f))
            inner = max(float(r["rho_err_avg_interior"]) for r in probe)
            inner_n = statistics.median(float(r["interior_count"]) for r in probe)
            fluid = s["fluid_particles"]
        else:
            err = err_max = inner = inner_n = float("nan")
            status, fluid = f"failed (exit {p.returncode})", 0
        ok, ok_inner = p.returncode == 0 and err < args.eta, p.returncode == 0 and inner < args.eta
        rows.append((handling, dt, status, err, ok, inner, ok_inner, inner_n, err_max, fluid))
        if ok and not failed_whole:
            best[handling] = dt
        if ok_inner and not failed_inner:
            best_inner[handling] = dt
        failed_whole, failed_inner = failed_whole or not ok, failed_inner or not ok_inner
        if failed_whole and failed_inner:
            break
lines = [f"{rows[0][9] if rows else 0} fluid particles, constant Δt, 3 iterations, 0-{args.end:g} s; "
         "ρ_err = max(ρ/ρ0 − 1, 0); interior: fluid particles with no boundary particle within h",
         "",
         "| boundary | Δt (s) | outcome | max(ρ_err_avg) | below 1 % | max(ρ_err_avg), interior | below 1 % | interior particles (median) | max ρ_err |",
         "|---|---|---|---|---|---|---|---|---|"]
for h, dt, st, err, ok, inner, ok_inner, inner_n, err_max, fluid in rows:
    lines.append(f"| {h} | {dt:g} | {st} | {100 * err:.2f} % | {'yes' if ok else 'no'} | {100 * inner:.2f} % | "
                 f"{'yes' if ok_inner else 'no'} | {inner_n:.0f} | {100 * err_max:.2f} % |")
lines.append("")
for h in ("ihmsen", "direct_forcing"):
    lines.append(f"largest Δt below {100 * args.eta:g} %: {h}: whole fluid {best.get(h, 'none of the steps tried')}, "
                 f"interior {best_inner.get(h, 'none of the steps tried')}")
text = "\n".join(lines) + "\n"
print(text)
(out_root / "boundary_sweep.md").write_text(text)
