#!/usr/bin/python3
"""resolution_study: how a scene's error against its experiment changes with the particle
spacing, and how much of it is run-to-run scatter.

usage: tools/resolution_study.py SCENE.json [--refine 0.5,0.75,1,1.5] [--runs 6]
           [--perturb simulation.stepping.lambda_c=0.36:0.44] [--mode global] [--set KEY=VALUE ...]
           [--vary KEY=V1,V2,... (one value per refinement factor)]
           [--end T] [--threads 2] [--free-shift 1.0] [--out out/resolution/<scene>]
           [--sph-run build/tools/sph-run]

For every refinement factor f (the spacing is the scene's divided by f, so the particle count
is multiplied by f^3) it runs the scene --runs times with sph-run, one run after another,
with the --perturb key spread evenly over its range (by default the acoustic CFL coefficient
lambda_c over 0.4 +- 10 %, which changes the step sequence and nothing in the model). A free
surface flow is chaotic at the scale of a particle, so one run per resolution cannot tell a
trend from scatter; the spread of the perturbed runs measures the scatter.

For every probe with an `experiment` object (scenes/README.md) it writes, per resolution:
  * the error of each run against the experiment (RMS relative over t_range with one time
    shift |dT| <= max_shift, as sph-study computes it): median, minimum, maximum;
  * the error of the runs' mean curve, its shift, and the best shift when it may reach
    --free-shift (a lead or lag the bounded shift cannot absorb shows as a shift at the bound);
  * the scatter: RMS over t_range of the runs' standard deviation relative to their mean;
  * the change from the next coarser resolution: RMS relative difference of the mean curves
    over t_range, no shift (a discretisation that converges makes these fall geometrically);
  * the largest absolute deviation from the measured points in t_range, no shift, per run:
    median, minimum, maximum (the Martin & Moyce residual-height criterion, |d eta| <= 0.05).

Outputs in --out: resolution.md, resolution.csv, resolution.png (error against spacing and
the mean curves against the data), and every run's folder f<f>/run<k>/.

When and failures. resolution.md and resolution.csv are rewritten after every run (into a
temporary file in --out, then renamed onto the table: never half-written), so an interrupted or
crashed study keeps the figures of the runs it finished; a resolution whose runs are not all done
yet has the status "k of N runs run so far". resolution.png is drawn at the end. A run sph-run
reports failed ("failed (exit N)"), stopped by a signal ("interrupted (...)"), or whose
summary.json or probe files cannot be read ("unreadable: <file>: <reason>"), is left out of its
resolution's figures and named in the row's `status` (CSV) and under the table; a resolution
with no usable run is a row with only that status. Every run's output goes to its run.log. The
experiments' files are read once, before any run. Exit codes: 0 every run usable; 2 bad
arguments or an experiment file that cannot be read, before any run, or, after writing the
tables, a run not usable (one line, `resolution_study.py: error: ...`); 130 / 143 interrupted
(Ctrl-C / SIGTERM: the running sph-run is stopped and waited for).
"""
import argparse
import datetime
import json
import pathlib
import sys
import time

from sph_python import csv_text, errors_as_exit_2, exit_if_unusable, fail, log_tail, md_status_row, need, sph_run, \
    write_atomic  # noqa: E402 (tools/ is the script's folder)
errors_as_exit_2()

need("numpy")
import numpy as np  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from sph_study import experiment_series, full_key, machine, read_experiments, shifted_error, source_commit  # noqa: E402


def parse_perturb(spec):
    key, _, rng = spec.partition("=")
    lo, _, hi = rng.partition(":")
    try:
        return full_key(key.strip()), float(lo), float(hi)
    except ValueError:
        fail(f"--perturb '{spec}': expected KEY=LOW:HIGH, e.g. simulation.stepping.lambda_c=0.36:0.44")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=next(p for p in __doc__.split("\n\n") if p.startswith("When and failures.")))
    ap.add_argument("scene")
    ap.add_argument("--refine", default="0.5,0.75,1,1.5",
                    help="linear refinement factors; spacing = scene spacing / f (default 0.5,0.75,1,1.5)")
    ap.add_argument("--runs", type=int, default=6, help="perturbed runs per resolution (default 6)")
    ap.add_argument("--perturb", default="simulation.stepping.lambda_c=0.36:0.44",
                    help="KEY=LOW:HIGH spread over the runs (default simulation.stepping.lambda_c=0.36:0.44)")
    ap.add_argument("--vary", action="append", default=[],
                    help="KEY=V1,V2,... one value per --refine factor, in --refine's order (e.g. "
                         "fluid.support=2,2.45,3 to grow the kernel support as the spacing falls)")
    ap.add_argument("--mode", help="stepping mode (default: the scene's)")
    ap.add_argument("--set", action="append", default=[], help="override for every run")
    ap.add_argument("--end", type=float, help="simulated seconds (default: the scene's end_time)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--free-shift", type=float, default=1.0, help="largest |dT| of the unbounded shift (default 1)")
    ap.add_argument("--out", help="output folder (default out/resolution/<scene name>)")
    ap.add_argument("--sph-run", default=str(HERE.parent / "build" / "tools" / "sph-run"))
    args = ap.parse_args()

    scene_path = pathlib.Path(args.scene)
    try:
        scene = json.loads(scene_path.read_text())
    except (OSError, ValueError) as e:
        fail(f"{scene_path}: {e}")
    probes = [p for p in scene.get("probes", []) if isinstance(p, dict) and "experiment" in p]
    if not probes:
        fail(f"{scene_path}: no probe has an `experiment` object; nothing to compare")
    try:
        factors = [float(f) for f in args.refine.split(",")]
    except ValueError:
        fail(f"--refine '{args.refine}': expected comma-separated positive numbers, e.g. 0.5,1,1.5")
    if any(not f > 0 for f in factors):
        fail(f"--refine '{args.refine}': every factor must be > 0")
    if args.runs < 1:
        fail(f"--runs {args.runs}: expected at least 1")
    per_factor = {f: [] for f in factors}  # --vary: the overrides of each refinement
    for spec in args.vary:
        k, _, vals = spec.partition("=")
        vals = [v.strip() for v in vals.split(",")]
        if not k or len(vals) != len(factors) or not all(vals):
            fail(f"--vary '{spec}': expected KEY=V1,...,V{len(factors)}, one value per --refine factor")
        for f, v in zip(factors, vals):
            per_factor[f].append(f"{full_key(k.strip())}={v}")
    factors.sort()
    key, lo, hi = parse_perturb(args.perturb)
    values = [0.5 * (lo + hi)] if args.runs == 1 else list(np.linspace(lo, hi, args.runs))
    base_scale = float(scene.get("simulation", {}).get("scale", 1.0))
    out = pathlib.Path(args.out or f"out/resolution/{scene.get('name', scene_path.stem)}")
    sph_run_path = pathlib.Path(args.sph_run)
    if not sph_run_path.exists():
        fail(f"{sph_run_path}: not found (build the project first, or pass --sph-run)")
    measured = read_experiments(scene_path, probes)  # once, before any run: a bad file stops the study now
    out.mkdir(parents=True, exist_ok=True)

    started = time.time()
    runs = {}      # factor -> [(run dir, summary, {probe name: experiment_series(...)})] of the usable runs
    problems = {}  # factor -> ["run<k>: failed (exit N)" or "run<k>: unreadable: <file>: <reason>"]
    total = len(factors) * len(values)
    for fi, f in enumerate(factors):
        runs[f], problems[f] = [], []
        for k, v in enumerate(values):
            d = out / f"f{f:g}" / f"run{k}"
            cmd = [str(sph_run_path), str(scene_path), "--scale", repr(base_scale * f ** 3), "--threads",
                   str(args.threads), "--no-frames", "-q", "--out", str(d), "--set", f"{key}={v!r}"]
            if args.mode:
                cmd += ["--mode", args.mode]
            if args.end is not None:
                cmd += ["--end", repr(args.end)]
            for s in args.set:
                cmd += ["--set", full_key(s)]
            for s in per_factor[f]:
                cmd += ["--set", s]
            n = fi * len(values) + k + 1
            print(f"[{n}/{total}] refine {f:g}{''.join(', ' + s for s in per_factor[f])}, {key} = {v:.4g} ...",
                  end=" ", flush=True)
            t0 = time.time()
            result, problem = sph_run(cmd, d, numbers=("fluid_particles", "kept_steps", "physics.particle_radius"),
                                      then=lambda s: (s, {p["name"]: experiment_series(d, p, measured[p["name"]])
                                                          for p in probes}))
            if problem:
                print(f"{problem}: {' '.join(cmd)}\n{log_tail(d)}", flush=True)
                problems[f].append(f"run{k}: {problem}")
            else:
                summary, series = result
                print(f"{summary['fluid_particles']:,} particles, {summary['kept_steps']:,} steps, "
                      f"{time.time() - t0:.1f} s", flush=True)
                runs[f].append((d, summary, series))
            rows, curves = tabulate(probes, factors, runs, problems, args)
            write_tables(out, rows, probes, scene_path, args, key, lo, hi, started)

    rows, curves = tabulate(probes, factors, runs, problems, args)
    text = write_tables(out, rows, probes, scene_path, args, key, lo, hi, started)
    print(text)
    wrote = [out / "resolution.md", out / "resolution.csv"]
    if any(runs.values()):
        plot(out / "resolution.png", probes, factors, rows, curves, runs, scene_path)
        wrote.append(out / "resolution.png")
    print("wrote " + ", ".join(str(w) for w in wrote))
    exit_if_unusable([f"refine {f:g} {p}" for f in factors for p in problems[f]],
                     f"{out / 'resolution.csv'} and resolution.md", total=total)


COLUMNS = ["probe", "refine", "spacing_m", "length_per_spacing", "particles", "runs", "steps_median", "err_median",
           "err_min", "err_max", "mean_err", "mean_shift", "free_err", "free_shift", "scatter", "change", "max_shift",
           "max_abs_median", "max_abs_min", "max_abs_max", "status"]


def tabulate(probes, factors, runs, problems, args):
    """Rows (per probe and resolution begun) and curves of the usable runs so far."""
    rows = []
    curves = {}  # (probe, factor) -> (T grid, mean Z, per-run errors against the experiment)
    for p in probes:
        e = p["experiment"]
        t_range = e.get("t_range", [-1e300, 1e300])
        max_shift = e.get("max_shift", 0.0)
        prev = None
        for f in factors:
            if f not in runs:
                break  # not begun
            tried = len(runs[f]) + len(problems[f])
            parts = [] if tried == args.runs else [f"{tried} of {args.runs} runs run so far"]
            if problems[f]:
                parts.append(f"{len(runs[f])} of {tried} runs usable; " + "; ".join(problems[f]))
            status = "; ".join(parts) or "ok"
            if not runs[f]:
                rows.append({"probe": p["name"], "refine": f, "runs": 0, "status": status})
                prev = None  # no change "from the next coarser" across a missing resolution
                continue
            series = [sr[p["name"]] for _, _, sr in runs[f]]
            te, ze = series[0][2], series[0][3]
            t_end = min(s[0][-1] for s in series)
            grid = np.linspace(max(s[0][0] for s in series), t_end, 2000)
            zs = np.array([np.interp(grid, s[0], s[1]) for s in series])
            mean = zs.mean(axis=0)
            per_run = [shifted_error(s[0], s[1], te, ze, t_range, max_shift)[0] for s in series]
            curves[(p["name"], f)] = (grid, mean, per_run)
            inside = (te >= t_range[0]) & (te <= t_range[1]) & (te <= t_end)
            max_abs = [float(np.max(np.abs(np.interp(te[inside], s[0], s[1]) - ze[inside]))) if inside.any()
                       else float("nan") for s in series]  # nan: the runs end before the measured range
            mean_err, mean_shift = shifted_error(grid, mean, te, ze, t_range, max_shift)
            free_err, free_shift = shifted_error(grid, mean, te, ze, t_range, max(args.free_shift, max_shift), max_shift)
            w = (grid >= t_range[0]) & (grid <= t_range[1])
            sd = zs.std(axis=0, ddof=1) if len(zs) > 1 else np.zeros_like(mean)
            scatter = float(np.sqrt(np.mean((sd[w] / mean[w]) ** 2)))
            change = float("nan")
            if prev is not None:
                pg, pm = prev
                change = float(np.sqrt(np.mean(((np.interp(grid[w], pg, pm) - mean[w]) / mean[w]) ** 2)))
            prev = (grid, mean)
            s0 = runs[f][0][1]
            spacing = 2 * s0["physics"]["particle_radius"]
            rows.append({
                "probe": p["name"], "refine": f, "spacing_m": spacing,
                "length_per_spacing": 1 / (spacing * e.get("value_scale", 1.0)),
                "particles": s0["fluid_particles"], "runs": len(series),
                "steps_median": float(np.median([s["kept_steps"] for _, s, _ in runs[f]])),
                "err_median": float(np.median(per_run)), "err_min": min(per_run), "err_max": max(per_run),
                "mean_err": mean_err, "mean_shift": mean_shift, "free_err": free_err, "free_shift": free_shift,
                "scatter": scatter, "change": change, "max_shift": max_shift,
                "max_abs_median": float(np.median(max_abs)), "max_abs_min": min(max_abs), "max_abs_max": max(max_abs),
                "status": status,
            })
    return rows, curves


def write_tables(out, rows, probes, scene_path, args, key, lo, hi, started):
    """resolution.csv and resolution.md of the rows so far, each replaced atomically; returns the Markdown."""
    write_atomic(out / "resolution.csv", csv_text(rows, COLUMNS))
    pct = lambda x: "–" if x != x else f"{100 * x:.2f}"  # noqa: E731 (nan -> dash)
    varied = "".join(f"; `{s}` per refinement" for s in args.vary)
    lines = [f"`{scene_path.name}`{varied}, {args.mode or 'scene mode'}, {args.runs} run(s) per resolution with "
             f"`{key}` from {lo:g} to {hi:g}, {args.threads} threads, {machine()}, "
             f"{datetime.datetime.now():%Y-%m-%d %H:%M}, engine {source_commit()}; "
             f"{time.time() - started:.0f} s in all.", ""]
    for p in probes:
        e = p["experiment"]
        lines += [f"Probe `{p['name']}` against `{e['file'].split('/')[-1]}` (RMS relative error over "
                  f"{e.get('t_range')}, one shift |ΔT| ≤ {e.get('max_shift', 0.0):g}):", "",
                  "| spacing | L / spacing | particles | steps (median) | error per run % median (min–max) | "
                  "mean curve error % (ΔT) | free shift: error % (ΔT) | scatter % | change from coarser % | "
                  "max \\|Δ\\| per run, no shift: median (min–max) |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        mine = [r for r in rows if r["probe"] == p["name"]]
        for r in mine:
            if not r["runs"]:
                lines.append(md_status_row(f"refine {r['refine']:g}", r["status"], 10))
                continue
            lines.append(
                f"| {1e3 * r['spacing_m']:.3g} mm | {r['length_per_spacing']:.1f} | {r['particles']:,} | "
                f"{r['steps_median']:,.0f} | {pct(r['err_median'])} ({pct(r['err_min'])}–{pct(r['err_max'])}) | "
                f"{pct(r['mean_err'])} ({r['mean_shift']:+.3f}) | {pct(r['free_err'])} ({r['free_shift']:+.3f}) | "
                f"{pct(r['scatter'])} | {pct(r['change'])} | "
                f"{r['max_abs_median']:.3f} ({r['max_abs_min']:.3f}–{r['max_abs_max']:.3f}) |")
        notes = [f"* refine {r['refine']:g}: {r['status']}" for r in mine if r["runs"] and r["status"] != "ok"]
        lines += [""] + notes + ([""] if notes else [])
    text = "\n".join(lines)
    write_atomic(out / "resolution.md", text)
    return text


def plot(path, probes, factors, rows, curves, runs, scene_path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(probes), 2, figsize=(11, 3.6 * len(probes)), squeeze=False)
    for i, p in enumerate(probes):
        mine = [r for r in rows if r["probe"] == p["name"] and r["runs"]]
        ax = axes[i][0]
        x = [r["length_per_spacing"] for r in mine]
        for r in mine:
            errs = curves[(p["name"], r["refine"])][2]
            ax.plot([r["length_per_spacing"]] * len(errs), [100 * v for v in errs], "o", color="0.6", ms=4)
        ax.plot(x, [100 * r["mean_err"] for r in mine], "-s", label="mean curve, bounded shift")
        ax.plot(x, [100 * r["free_err"] for r in mine], "--^", label="mean curve, free shift")
        ax.plot(x[1:], [100 * r["change"] for r in mine[1:]], ":d", label="change from coarser")
        ax.set_xscale("log")
        ax.set_xticks(x, [f"{v:.3g}" for v in x])
        ax.minorticks_off()
        ax.set_xlabel("experiment length / particle spacing")
        ax.set_ylabel("RMS relative error %")
        ax.set_title(f"{p['name']}: error against spacing (grey: single runs)")
        ax.legend(fontsize=8)
        ax = axes[i][1]
        for r in mine:
            grid, mean, _ = curves[(p["name"], r["refine"])]
            ax.plot(grid, mean, label=f"1/{r['length_per_spacing']:.0f} (mean of {r['runs']})")
        _, _, te, ze = next(sr[p["name"]] for f in factors for _, _, sr in runs[f])
        ax.plot(te, ze, "ko", ms=4, label="experiment")
        ax.set_xlabel("T (dimensionless time)")
        ax.set_ylabel("Z (dimensionless)")
        ax.set_title(f"{p['name']}: mean curves, no shift")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
