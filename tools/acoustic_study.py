#!/usr/bin/env python3
"""Runs a scene in `global` mode with and without the acoustic step condition, at two
artificial viscosities, and prints a Markdown table (the README's stability measurement).

usage: tools/acoustic_study.py [SCENE.json ...] [--sph-run build/tools/sph-run] [--out out/acoustic_study]
Runs are sequential so that wall times compare; each run's outputs (and its run.log) are kept in
--out. Ctrl-C or SIGTERM stops the running sph-run (sph_python.run_child: it runs in its own
session and gets one SIGTERM, so it finishes its step and saves its outputs) and ends the tool
by that signal.
"""
import argparse
import json
import pathlib
import sys
import time
from sph_python import errors_as_exit_2, positive_list, run_child  # noqa: E402 (tools/ is the script's folder)

errors_as_exit_2()

ap = argparse.ArgumentParser()
ap.add_argument("scenes", nargs="*", default=["scenes/dam_break.json"])
ap.add_argument("--sph-run", default="build/tools/sph-run")
ap.add_argument("--out", default="out/acoustic_study")
ap.add_argument("--viscosities", default="0.02,0.1")
args = ap.parse_args()
VISCOSITIES = positive_list(args.viscosities, "--viscosities", allow_zero=True)

rows = []
for scene in args.scenes:
  stem = pathlib.Path(scene).stem
  for alpha in VISCOSITIES:
    for acoustic in (True, False):
        name = f"{stem}_alpha{alpha}_{'acoustic' if acoustic else 'eq6-8_only'}"
        out = pathlib.Path(args.out) / name
        cmd = [args.sph_run, scene, "--mode", "global", "--no-frames", "-q", "--out", str(out),
               "--set", f"fluid.viscosity={alpha}", "--set", f"simulation.stepping.acoustic={'true' if acoustic else 'false'}"]
        print("running:", " ".join(cmd), file=sys.stderr, flush=True)
        t0 = time.time()
        out.mkdir(parents=True, exist_ok=True)
        returncode = run_child(cmd, out / "run.log")
        wall = time.time() - t0
        last = ((out / "run.log").read_text(errors="replace").strip().splitlines() or [""])[-1]
        if returncode not in (0, 3):
            # Not a run that went unstable (exit 3 keeps its outputs up to the failure) but bad input
            # or a broken run: its folder may hold an earlier run's outputs, so none is read.
            print(f"acoustic_study.py: error: {' '.join(cmd)} exited {returncode}: {last}", file=sys.stderr)
            sys.exit(2 if returncode == 2 else 1)
        summary = json.loads((out / "summary.json").read_text()) if (out / "summary.json").exists() else {}
        stats = (out / "stats.csv").read_text().splitlines() if (out / "stats.csv").exists() else []
        header = stats[0].split(",") if stats else []
        max_err = 0.0
        if header:
            k = header.index("rho_err_max")
            max_err = max(float(line.split(",")[k]) for line in stats[1:]) if len(stats) > 1 else 0.0
        outcome = "completed" if returncode == 0 else f"failed (exit {returncode})"
        detail = last if returncode else ""
        rows.append((stem, alpha, acoustic, outcome, summary.get("simulated_time_s", 0.0), summary.get("steps", len(stats) - 1),
                     summary.get("avg_dt_s", 0.0), max_err, wall, detail, summary.get("boundary_collisions_total", 0)))

print(f"Mode `global` (λv = 0.1, λf = 0.05, λc = 0.4 when on), date {time.strftime('%Y-%m-%d')}\n")
print("| scene | viscosity α | acoustic condition | outcome | simulated s | steps | avg Δt (ms) | max ρ error | wall collisions | wall s |")
print("|---|---|---|---|---|---|---|---|---|---|")
for stem, alpha, acoustic, outcome, t, steps, avg_dt, err, wall, detail, coll in rows:
    print(f"| {stem} | {alpha} | {'on' if acoustic else 'off (eq. 6-8 only)'} | {outcome} | {t:.3f} | {steps} | "
          f"{avg_dt * 1e3:.3f} | {100 * err:.1f} % | {coll} | {wall:.1f} |")
for r in rows:
    if r[9]:
        print(f"\n- {r[0]}, α = {r[1]}, acoustic {'on' if r[2] else 'off'}: `{r[9]}`")
