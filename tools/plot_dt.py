#!/usr/bin/env python3
"""Plots a run's simulation step Δt_sim (log scale) and the fraction of active particles over
simulated time from its stats.csv, like He et al. Fig. 2; several runs are overlaid.

usage: tools/plot_dt.py RUN [RUN ...] [--label NAME ...] [--out dt_plot.png]
                        [--width PX] [--height PX] [--smooth SECONDS] [--title TEXT]

RUN is a stats.csv or a run directory holding one (sph-run's --out). Labels default to the
run's stepping mode from its summary.json (else the directory name). The active fraction is
drawn per step (thin) and averaged over --smooth simulated seconds (thick; default 0.01 s,
0 turns it off). The last step, when the runner shortened it to land on the end time (it ends on
summary.json's simulated_time_s and is shorter than the step before), is left out so the
curve does not dip at the end.
Exit codes: 0 ok, 2 bad input (missing file, stats.csv without the expected columns).
"""
import argparse
import csv
import json
import pathlib
import sys

from sph_python import errors_as_exit_2, need  # noqa: E402 (tools/ is the script's folder)
errors_as_exit_2()

need("numpy")
import numpy as np  # noqa: E402

REQUIRED = ("step", "t", "dt", "active_fraction")


class InputError(Exception):
    pass


def load_run(arg):
    p = pathlib.Path(arg)
    csv_path = p / "stats.csv" if p.is_dir() else p
    if not csv_path.is_file():
        if p.is_dir():
            raise InputError(f"{csv_path}: no such file (expected a run directory holding stats.csv)")
        raise InputError(f"{p}: no such file or directory (expected a stats.csv or a run directory holding one)")
    with open(csv_path, newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise InputError(f"{csv_path}: empty, expected a header line with {', '.join(REQUIRED)}")
    header = [h.strip() for h in rows[0]]
    missing = [c for c in REQUIRED if c not in header]
    if missing:
        raise InputError(f"{csv_path}: missing column(s) {', '.join(missing)}; expected sph-run's stats.csv with "
                         f"{', '.join(REQUIRED)}, found {', '.join(header[:8])}{', ...' if len(header) > 8 else ''}")
    body = [r for r in rows[1:] if r]
    if not body:
        raise InputError(f"{csv_path}: no steps recorded (header only)")
    cols = {}
    for c in REQUIRED:
        k = header.index(c)
        try:
            cols[c] = np.array([float(r[k]) for r in body])
        except (ValueError, IndexError):
            line = next(i for i, r in enumerate(body, start=2) if len(r) <= k or not _is_float(r[k]))
            raise InputError(f"{csv_path}: line {line}: column {c} is not a number") from None
    summary = {}
    sfile = csv_path.parent / "summary.json"
    if sfile.is_file():
        try:
            summary = json.loads(sfile.read_text())
        except json.JSONDecodeError:
            summary = {}
    # The runner shortens the last step to land on the end time. stats.csv does not say so;
    # a last step that ends on the run's simulated time and is shorter than the step before
    # it (or than every step the conditions allowed, summary min_dt_s) is taken as clipped.
    clipped = False
    dt, t = cols["dt"], cols["t"]
    steps = len(dt)
    if len(dt) > 1 and "simulated_time_s" in summary:
        ends_on_end = abs(t[-1] + dt[-1] - summary["simulated_time_s"]) <= 1e-9 * max(1.0, summary["simulated_time_s"])
        if ends_on_end and (dt[-1] < dt[-2] or dt[-1] < summary.get("min_dt_s", 0.0)):
            clipped = True
            cols = {c: v[:-1] for c, v in cols.items()}
    return {"path": csv_path, "summary": summary, "clipped": clipped, "steps": steps, **cols}


def _is_float(s):
    try:
        float(s)
        return True
    except ValueError:
        return False


def smooth_by_time(t, y, window):
    """Mean of y over the steps whose start lies in [t - window/2, t + window/2]."""
    c = np.concatenate([[0.0], np.cumsum(y)])
    lo = np.searchsorted(t, t - window / 2, side="left")
    hi = np.searchsorted(t, t + window / 2, side="right")
    return (c[hi] - c[lo]) / np.maximum(hi - lo, 1)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="stats.csv files or run directories")
    ap.add_argument("--label", action="append", default=[], help="label of each run, in order (repeatable)")
    ap.add_argument("--out", default="dt_plot.png", help="PNG to write (default dt_plot.png)")
    ap.add_argument("--width", type=int, default=900, help="image width in pixels (default 900)")
    ap.add_argument("--height", type=int, default=600, help="image height in pixels (default 600)")
    ap.add_argument("--smooth", type=float, default=0.01,
                    help="window for the averaged active fraction, simulated seconds (default 0.01; 0: off)")
    ap.add_argument("--title", default=None, help="figure title (default: the scene name)")
    args = ap.parse_args(argv)

    def fail(msg):
        print(f"plot_dt.py: {msg}", file=sys.stderr)
        return 2

    if args.label and len(args.label) != len(args.runs):
        return fail(f"{len(args.label)} --label given for {len(args.runs)} runs; expected one per run or none")
    if args.width < 200 or args.height < 200:
        return fail(f"--width {args.width} --height {args.height}: expected at least 200 x 200 px")
    if args.smooth < 0:
        return fail(f"--smooth {args.smooth:g}: expected seconds >= 0")
    try:
        runs = [load_run(r) for r in args.runs]
    except InputError as e:
        return fail(str(e))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dpi = 100
    fig, (ax_dt, ax_act) = plt.subplots(2, 1, sharex=True, figsize=((args.width + 0.01) / dpi, (args.height + 0.01) / dpi),
                                        dpi=dpi, gridspec_kw={"height_ratios": [3, 2]})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, run in enumerate(runs):
        label = args.label[i] if args.label else run["summary"].get("stepping", run["path"].parent.name)
        c = colours[i % len(colours)]
        steps = run["steps"]
        avg_dt = run["summary"].get("avg_dt_s", run["dt"].mean())  # simulated time / steps, as summary.json
        ax_dt.plot(run["t"], run["dt"], color=c, lw=1.0,
                   label=f"{label}: {steps} steps, mean Δt$_{{sim}}$ {avg_dt * 1e3:.3g} ms")
        frac = 100.0 * run["active_fraction"]
        ax_act.plot(run["t"], frac, color=c, lw=0.4, alpha=0.35)
        mean_frac = frac.mean()
        if args.smooth > 0:
            ax_act.plot(run["t"], smooth_by_time(run["t"], frac, args.smooth), color=c, lw=1.8,
                        label=f"{label}: {mean_frac:.1f} % on average ({args.smooth:g} s mean drawn)")
        else:
            ax_act.lines[-1].set(alpha=1.0, lw=1.0, label=f"{label}: {mean_frac:.1f} % on average")
        note = " (the last, clipped to the end time, not drawn)" if run["clipped"] else ""
        print(f"{run['path']}: {label}, {steps} steps{note}, Δt_sim {run['dt'].min():.4g} .. {run['dt'].max():.4g} s, "
              f"mean active {mean_frac:.2f} %")
    ax_dt.set_yscale("log")
    ax_dt.set_ylabel("Δt$_{sim}$ (s)")
    ax_dt.grid(True, which="both", alpha=0.3)
    ax_dt.legend(fontsize=8, loc="best")
    ax_act.set_ylabel("active particles (%)")
    ax_act.set_xlabel("simulated time t (s)")
    ax_act.set_ylim(0, 105)
    ax_act.grid(True, alpha=0.3)
    ax_act.legend(fontsize=8, loc="best")
    title = args.title if args.title is not None else runs[0]["summary"].get("scene", "")
    if title:
        fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    out = pathlib.Path(args.out)
    if out.parent != pathlib.Path(""):
        out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    print(f"wrote {out} ({args.width} x {args.height} px)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
