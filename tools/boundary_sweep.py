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

When and failures. boundary_sweep.md is rewritten after every run (into a temporary file in
--out, then renamed onto it: never half-written), so an interrupted or crashed sweep keeps the
rows of the runs it finished. A run sph-run reports failed is a row "failed (exit N)", as a step
too large; a run stopped by a signal ("interrupted (...)") or that exits 0 but whose summary.json
or probes/fluid.csv cannot be read (missing, truncated, not JSON or CSV: "unreadable: <file>:
<reason>") is a marked row and ends its handling's sweep like a failed step (the largest Δt found
is then a lower bound). Every run's output goes to its run.log. Exit codes: 0 every run readable
(failed steps included); 2 bad arguments, or, after writing the table, a run unreadable or
interrupted (one line, `boundary_sweep.py: error: ...`); 130 / 143 interrupted (Ctrl-C /
SIGTERM: the running sph-run is stopped and waited for).
"""
import argparse
import json
import pathlib
import statistics
import sys
import time
from sph_python import errors_as_exit_2, exit_if_unusable, log_tail, md_cell, positive_list, read_csv_columns, \
    require, scene_copy, sph_run, write_atomic  # noqa: E402 (tools/ is the script's folder)

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
unusable = []  # "<handling> Δt <dt>: unreadable: <file>: <reason>" (or interrupted)
best = {}        # handling -> largest dt passing on the whole-fluid average (the paper's measure)
best_inner = {}  # handling -> largest dt passing on the interior average (no wall within h)
scene = json.loads(pathlib.Path(args.scene).read_text())


def table():
    """The Markdown table of the runs so far."""
    fluid = next((r[9] for r in rows if r[9]), 0)
    lines = [f"{fluid} fluid particles, constant Δt, 3 iterations, 0-{args.end:g} s; "
             "ρ_err = max(ρ/ρ0 − 1, 0); interior: fluid particles with no boundary particle within h",
             "",
             "| boundary | Δt (s) | outcome | max(ρ_err_avg) | below 1 % | max(ρ_err_avg), interior | below 1 % | interior particles (median) | max ρ_err |",
             "|---|---|---|---|---|---|---|---|---|"]
    for h, dt, st, err, ok, inner, ok_inner, inner_n, err_max, _ in rows:
        lines.append(f"| {h} | {dt:g} | {md_cell(st)} | {100 * err:.2f} % | {'yes' if ok else 'no'} | "
                     f"{100 * inner:.2f} % | {'yes' if ok_inner else 'no'} | {inner_n:.0f} | {100 * err_max:.2f} % |")
    lines.append("")
    for h in ("ihmsen", "direct_forcing"):
        lines.append(f"largest Δt below {100 * args.eta:g} %: {h}: whole fluid {best.get(h, 'none of the steps tried')}, "
                     f"interior {best_inner.get(h, 'none of the steps tried')}"
                     + (" (a run was unreadable or interrupted: a lower bound)" if any(
                         r[0] == h and r[2].startswith(("unreadable", "interrupted")) for r in rows) else ""))
    return "\n".join(lines) + "\n"
for handling in ("ihmsen", "direct_forcing"):
    failed_whole = failed_inner = False
    for dt in DTS:
        out = out_root / f"{handling}_{dt:g}"
        out.mkdir(parents=True, exist_ok=True)
        # The scene with a fluid probe sampled every step (engine/run/probes.hpp: whole-fluid and
        # interior density errors). Written next to the outputs, its relative files (a mesh's OBJ)
        # made absolute from the scene's folder (scene_copy), so that it loads there.
        probed = scene_copy(scene, args.scene)
        probed["probes"] = [{"type": "fluid", "name": "fluid", "rate": 1.0 / dt}]
        scene_file = out / "scene.json"
        scene_file.write_text(json.dumps(probed, indent=1))
        cmd = [args.sph_run, str(scene_file), "--scale", str(args.scale), "--end", str(args.end), "--threads",
               str(args.threads), "--no-frames", "-q", "--out", str(out / "run"), "--mode", "constant", "--dt", repr(dt),
               "--set", f"boundary.handling={handling}", "--set", "pcisph.iterations=3", "--set", "pcisph.loop=fixed"]
        print(f"[{time.strftime('%H:%M:%S')}] {' '.join(cmd)}", file=sys.stderr, flush=True)
        result, status = sph_run(cmd, out / "run",
                                 numbers=("max_avg_density_error", "max_density_error", "fluid_particles"),
                                 then=lambda s: (s, read_csv_columns(out / "run" / "probes" / "fluid.csv",
                                                                     ("rho_err_avg_interior", "interior_count"),
                                                                     min_rows=1)))
        err = err_max = inner = inner_n = float("nan")
        fluid = 0
        if status is None:
            s, probe = result
            err, err_max, status = s["max_avg_density_error"], s["max_density_error"], "completed"
            inner = max(probe["rho_err_avg_interior"])
            inner_n = statistics.median(probe["interior_count"])
            fluid = s["fluid_particles"]
        elif status.startswith("failed"):
            print(f"boundary_sweep.py: run {status}:\n{log_tail(out / 'run')}", file=sys.stderr, flush=True)
        else:
            unusable.append(f"{handling} Δt {dt:g}: {status}")
            print(f"boundary_sweep.py: {status}", file=sys.stderr, flush=True)
        ok, ok_inner = status == "completed" and err < args.eta, status == "completed" and inner < args.eta
        rows.append((handling, dt, status, err, ok, inner, ok_inner, inner_n, err_max, fluid))
        if ok and not failed_whole:
            best[handling] = dt
        if ok_inner and not failed_inner:
            best_inner[handling] = dt
        failed_whole, failed_inner = failed_whole or not ok, failed_inner or not ok_inner
        text = table()
        write_atomic(out_root / "boundary_sweep.md", text)
        if failed_whole and failed_inner:
            break
text = table()
write_atomic(out_root / "boundary_sweep.md", text)
print(text)
exit_if_unusable(unusable, f"{out_root / 'boundary_sweep.md'}")
