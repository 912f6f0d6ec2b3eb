#!/usr/bin/python3
"""Ihmsen et al. 2010 Table 1 for PCISPH scenes: `adaptive` and `constant` stepping side by side,
run one after another (never in parallel) so the wall times compare.

usage: tools/pcisph_table.py SCENE.json [SCENE.json ...] [--end T] [--threads 2] [--scale S]
                             [--sph-run build/tools/sph-run] [--out out/pcisph_table] [--no-constant]

The `constant` run takes the paper's comparison step (sec. 4.2): eq. 14-15 with the maxima
v^max and F^max the adaptive run tracked over all its kept steps, lambda_v = 0.4 and
lambda_f = 0.25 (summary.json: pcisph.dt_eq14_15). Speed-up = constant wall / adaptive wall. The step
ratio (simulated time / Δt_const, over the adaptive run's kept steps) is the speed-up at equal
cost per step; with --no-constant it is the only ratio (the constant run is not made).
Writes pcisph_table.md / .csv into --out and, for every scene, dt_<scene>.png: the adaptive
step over simulated time (the paper's Fig. 4), rolled-back steps marked. Each run's output goes to
run.log in its folder; Ctrl-C or SIGTERM stops the running sph-run (one SIGTERM: it finishes its
step and saves its outputs) and ends the tool by that signal.
"""
import argparse
import csv
import json
import pathlib
import sys
import time
from sph_python import errors_as_exit_2, file_sha256, log_tail, run_child  # noqa: E402 (tools/ is the script's folder)

errors_as_exit_2()

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("scenes", nargs="+")
ap.add_argument("--end", type=float, default=None)
ap.add_argument("--scale", type=float, default=None)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--no-constant", action="store_true")
ap.add_argument("--sph-run", default="build/tools/sph-run")
ap.add_argument("--out", default="out/pcisph_table")
ap.add_argument("--set", action="append", default=[], help="extra --set for both runs")
ap.add_argument("--reuse", action="store_true",
                help="keep a run whose summary.json exists in --out if it was made by this same command "
                     "(the scene file unchanged, the same options); others are run again")
args = ap.parse_args()
if not pathlib.Path(args.sph_run).exists():
    sys.exit(f"{args.sph_run}: not found (build first)")
out_root = pathlib.Path(args.out)
out_root.mkdir(parents=True, exist_ok=True)


def run(scene, tag, sets):
    """A run's folder and summary. With --reuse, a folder whose summary.json exists is kept only
    when its `pcisph_table.json` records this very command (the scene file's absolute path, its
    contents' SHA-256 and every argument); another (or an unrecorded) run is made again, saying why."""
    out = out_root / f"{pathlib.Path(scene).stem}_{tag}"
    cmd = [args.sph_run, scene, "--threads", str(args.threads), "--no-frames", "-q", "--out", str(out)]
    if args.end is not None:
        cmd += ["--end", str(args.end)]
    if args.scale is not None:
        cmd += ["--scale", str(args.scale)]
    for s in args.set + sets:
        cmd += ["--set", s]
    record = {"scene": str(pathlib.Path(scene).resolve()),
              "scene_sha256": file_sha256(scene), "command": cmd[2:]}
    if args.reuse and (out / "summary.json").is_file():
        try:
            kept = json.loads((out / "pcisph_table.json").read_text())
        except (OSError, ValueError):
            kept = None
        if kept == record:
            print(f"reusing {out}", file=sys.stderr)
            return out, json.loads((out / "summary.json").read_text())
        why = ("no pcisph_table.json records its command" if not isinstance(kept, dict) else
               "the scene file has changed since (its SHA-256 differs)" if kept.get("command") == record["command"]
               and kept.get("scene") == record["scene"] else "another scene or other options")
        print(f"not reusing {out / 'summary.json'}: {why}; running it again", file=sys.stderr, flush=True)
    print(f"[{time.strftime('%H:%M:%S')}] {' '.join(cmd)}", file=sys.stderr, flush=True)
    out.mkdir(parents=True, exist_ok=True)
    (out / "pcisph_table.json").unlink(missing_ok=True)
    rc = run_child(cmd, out / "run.log")  # in its own session: Ctrl-C reaches this tool, which stops it (one SIGTERM)
    if rc != 0:
        sys.exit(f"run failed (exit {rc}): {' '.join(cmd)}\n{log_tail(out)}")
    (out / "pcisph_table.json").write_text(json.dumps(record, indent=1) + "\n")
    return out, json.loads((out / "summary.json").read_text())


def plot_dt(stats_dir, png, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    t, dt, rb = [], [], []
    with open(stats_dir / "stats.csv", newline="") as fh:
        for row in csv.DictReader(fh):
            t.append(float(row["t"]))
            dt.append(float(row["dt"]))
            rb.append(row["rolled_back"] == "1")
    # The last step is clipped to land on the end time: leave it out of the curve.
    fig, ax = plt.subplots(figsize=(7, 3.2), dpi=120)
    ax.plot([a for a, r in zip(t[:-1], rb) if not r], [d for d, r in zip(dt[:-1], rb) if not r], lw=1.0,
            color="#b22222", label="Δt (kept steps)")
    shocks = [(a, d) for a, d, r in zip(t, dt, rb) if r]
    if shocks:
        ax.scatter([a for a, _ in shocks], [d for _, d in shocks], marker="x", color="k", zorder=3,
                   label=f"shock: rolled back ({len(shocks)})")
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel("Δt (s)")
    ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png)
    plt.close(fig)


rows = []
for scene in args.scenes:
    a_dir, a = run(scene, "adaptive", ["simulation.stepping.mode=adaptive"])
    plot_dt(a_dir, out_root / f"dt_{a['scene']}.png", f"{a['scene']}: adaptive Δt (Ihmsen 2010 Fig. 4)")
    pc = a["pcisph"]
    row = {"scene": a["scene"], "fluid": a["fluid_particles"], "boundary": a["boundary_particles"],
           "simulated_s": a["simulated_time_s"], "adaptive_wall_s": a["wall_time_s"], "adaptive_steps": a["kept_steps"],
           "shocks": a["shocks"], "dt_min": a["min_dt_s"], "dt_max": a["max_dt_s"],
           "max_rho_err_avg": a["max_avg_density_error"], "max_rho_err": a["max_density_error"],
           "active_boundary_ratio": pc["avg_active_boundary_per_fluid"], "dt_const": pc["dt_eq14_15"],
           "v_max": pc["v_max_tracked"], "f_max": pc["a_max_tracked"],
           # What the speed-up would be at equal cost per step (both runs take 3 passes): the
           # constant run's step count follows from eq. 14-15 without running it (--no-constant).
           "step_ratio": a["simulated_time_s"] / pc["dt_eq14_15"] / a["kept_steps"] if pc["dt_eq14_15"] > 0 else 0.0}
    if not args.no_constant:
        _, c = run(scene, "constant", ["simulation.stepping.mode=constant", f"simulation.stepping.dt={pc['dt_eq14_15']!r}"])
        row.update({"constant_wall_s": c["wall_time_s"], "constant_steps": c["steps"],
                    "constant_max_rho_err_avg": c["max_avg_density_error"],
                    "speed_up": c["wall_time_s"] / a["wall_time_s"] if a["wall_time_s"] > 0 else 0.0})
    rows.append(row)

hdr = ("| scene | fluid / boundary particles | simulated s | adaptive wall s (steps, shocks) | constant wall s (steps) "
       "| Δt_min / Δt_max adaptive | Δt constant (eq. 14-15) | speed-up | max(ρ_err_avg) adaptive / constant "
       "| active boundary / fluid | step ratio T/Δt_const ÷ adaptive steps |")
lines = [hdr, "|" + "---|" * hdr.count("|")[:-1] if False else "|---|---|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    const = (f"{r['constant_wall_s']:.1f} ({r['constant_steps']:,})" if "constant_wall_s" in r else "–")
    speed = f"{r['speed_up']:.2f}" if "speed_up" in r else "–"
    cerr = f"{100 * r['constant_max_rho_err_avg']:.2f} %" if "constant_max_rho_err_avg" in r else "–"
    lines.append(f"| {r['scene']} | {r['fluid']:,} / {r['boundary']:,} | {r['simulated_s']:.2f} | "
                 f"{r['adaptive_wall_s']:.1f} ({r['adaptive_steps']:,}, {r['shocks']}) | {const} | "
                 f"{r['dt_min']:.5f} / {r['dt_max']:.5f} | {r['dt_const']:.5f} | {speed} | "
                 f"{100 * r['max_rho_err_avg']:.2f} % / {cerr} | {100 * r['active_boundary_ratio']:.1f} % | "
                 f"{r['step_ratio']:.2f} |")
text = "\n".join(lines) + "\n"
print(text)
(out_root / "pcisph_table.md").write_text(text)
with open(out_root / "pcisph_table.csv", "w", newline="") as fh:
    keys = sorted({k for r in rows for k in r})
    w = csv.DictWriter(fh, fieldnames=keys)
    w.writeheader()
    w.writerows(rows)
