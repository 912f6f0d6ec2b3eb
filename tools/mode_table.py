#!/usr/bin/env python3
"""He et al. Table 1 for one scene: `constant`, `global` and `individual` stepping side by side,
at one or more sizes, run one after another (never in parallel) so the wall times compare.

usage: tools/mode_table.py SCENE.json [--scales 1,2] [--end T] [--threads 2] [--repeat 3]
                           [--sph-run build/tools/sph-run] [--out out/mode_table]
                           [--set KEY=VALUE ...] [--extra NAME:KEY=VALUE,KEY=VALUE ...]

--set KEY=VALUE (repeatable) applies to every configuration, before its own settings (e.g.
--set simulation.stepping.lambda_c=0.8 to compare the modes at that acoustic coefficient; an
--extra's own KEY=VALUE wins where both set one key).

With --repeat K every configuration runs K times, interleaved round by round (global,
individual, ..., then again), and the table gives the median wall and CPU time, so a burst
of load from other processes hits one round of every mode instead of one mode. The runs
are deterministic (same steps and results each time); only the times vary.

The `constant` run uses the smallest step the `global` run of the same size took (its
`min_dt_s`), i.e. the largest fixed step known to be stable for the whole run, which is how
a user without adaptivity would have to choose it. It is also the table's reference for
accuracy: each configuration's RMS deviation from it of the scene's first `front` probe and of
its kinetic energy (a `fluid` probe's), as sph-study computes a deviation (the run interpolated
linearly to the reference's sample times; sph_study.deviation), from each configuration's
first run (the runs are deterministic). S x f is the wall-time speed-up over `global` times the
average active fraction: 1 when a particle evaluation costs what it costs in `global`. Each run's outputs (and its run.log) stay in
--out/scale<S>_<name>/ (the name with spaces as `_` and brackets dropped: two --extra names that
give the same folder are refused). Prints a Markdown table and writes mode_table.md and
mode_table.csv into --out.

When and failures. mode_table.md and mode_table.csv are rewritten after every run (into a
temporary file in --out, then renamed onto the table: never half-written), so an interrupted or
crashed table keeps the configurations run so far (medians over the runs so far). A run sph-run
reports failed, stopped by a signal, or whose summary.json cannot be read, is left out of its
row's medians and named in the row's `status` (CSV) and under the table: "failed (exit N)",
"interrupted (<signal> at t = T s)", "unreadable: <file>: <reason>"; a configuration with no
usable run is a row with only that status, and without a usable first `global` run the
`constant` one is skipped. --reuse takes a summary.json only if it is readable, not marked
"interrupted", and of the run this invocation would make, as the run recorded it (summary.json's
`scene` and `threads`; its scene_as_run.json's simulation.end_time, simulation.scale and the
value of every KEY=VALUE of its configuration, the constant step included); any other is run
again, saying why ("not reusing <folder>/summary.json: another run's (simulation.end_time 0.02,
expected 0.3); running it again"), as is a run of the scene file before an edit (its SHA-256,
which mode_table.json records beside each run it makes; a folder without that record is taken
as the settings above say). Exit codes: 0 every run usable; 2 bad arguments (a
malformed --extra, say), before any run, or, after writing the tables, a run not usable (one
line, `mode_table.py: error: ...`); 130 / 143 interrupted (Ctrl-C / SIGTERM: the running sph-run
gets one SIGTERM, finishes its step and saves its outputs, summary.json marked "interrupted", and
is waited for).
"""
import argparse
import contextlib
import json
import math
import os
import pathlib
import platform
import statistics
import sys
import time
from sph_python import Unreadable, csv_text, errors_as_exit_2, exit_if_unusable, file_sha256, log_tail, md_cell, \
    md_status_row, positive_list, read_json_object, read_run, require, sph_run, write_atomic  # noqa: E402 (tools/ is the script's folder)
from sph_study import deviation, primary_series  # noqa: E402

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
                help="read a run's summary.json from --out if it is there, readable, not marked interrupted and of "
                     "the same scene, end time, scale, threads and configuration (as the run recorded them) instead "
                     "of running it again (re-tabulates an earlier or interrupted table with the same options); "
                     "any other is run again, saying why")
ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                help="a setting for every configuration, before its own (sph-run --set)")
ap.add_argument("--extra", action="append", default=[],
                help="an extra configuration NAME:KEY=VALUE[,KEY=VALUE...], e.g. 'individual(global λ):"
                     "simulation.stepping.mode=individual,simulation.stepping.lambda_v=0.1'")
args = ap.parse_args()
SCALES = positive_list(args.scales, "--scales")
require(args.repeat >= 1, f"--repeat {args.repeat}: expected at least 1")


def parse_extra(spec, taken):
    """NAME:KEY=VALUE,... -> (NAME, [KEY=VALUE, ...]); exit 2 naming the spec otherwise."""
    form = "expected NAME:KEY=VALUE[,KEY=VALUE...], e.g. 'lv0.1:simulation.stepping.mode=individual," \
           "simulation.stepping.lambda_v=0.1'"
    name, colon, rest = spec.partition(":")
    name = name.strip()
    require(colon, f"--extra {spec!r}: no ':' after the name; {form}")
    require(name, f"--extra {spec!r}: empty name; {form}")
    require(name not in taken, f"--extra {spec!r}: the name {name!r} is taken (global, constant, individual "
                               f"and each --extra need their own); {form}")
    sets = [s.strip() for s in rest.split(",") if s.strip()]
    require(sets, f"--extra {spec!r}: no KEY=VALUE after the ':'; {form}")
    for s in sets:
        key, eq, _ = s.partition("=")
        require(eq and key.strip(), f"--extra {spec!r}: {s!r} is not KEY=VALUE; {form}")
    return name, sets


def folder(name):
    """A configuration's run folder name (under --out/scale<S>_)."""
    return name.replace(' ', '_').replace('(', '').replace(')', '')


for spec in args.set:  # refused before any run
    key, eq, _ = spec.partition("=")
    require(eq and key.strip(), f"--set {spec!r}: not KEY=VALUE (e.g. simulation.stepping.lambda_c=0.8)")
EXTRAS = []
folders = {folder(n): n for n in ("global", "constant", "individual")}
for spec in args.extra:  # refused before any run
    EXTRAS.append(parse_extra(spec, {"global", "constant", "individual"} | {n for n, _ in EXTRAS}))
    name = EXTRAS[-1][0]
    require(folder(name) not in folders, f"--extra {spec!r}: the name {name!r} and {folders.get(folder(name))!r} "
                                         f"share the run folder scale<S>_{folder(name)} (spaces become '_', brackets "
                                         f"are dropped): give them names that differ otherwise")
    folders[folder(name)] = name

require(pathlib.Path(args.sph_run).exists(), f"{args.sph_run}: not found (build first: cmake --build build)")
out_root = pathlib.Path(args.out)
out_root.mkdir(parents=True, exist_ok=True)
SUMMARY_NUMBERS = ("wall_time_s", "steps", "fluid_particles", "simulated_time_s", "avg_dt_s", "min_dt_s", "max_dt_s",
                   "avg_active_fraction", "max_density_error", "boundary_collisions_total")


def override(assignment):
    """A --set KEY=VALUE as sph-run reads it (engine/data/scene_overrides.cpp parse_override):
    (the JSON pointer's keys, the value: JSON if it parses, else the bare word)."""
    key, _, text = assignment.partition("=")
    key, text = key.strip(), text.strip()
    if key.startswith("/"):
        path = [t.replace("~1", "/").replace("~0", "~") for t in key[1:].split("/")]
    else:
        path = key.split(".")
    try:
        value = json.loads(text)
    except ValueError:
        value = text
    return path, value


def same(recorded, wanted):
    """A recorded setting equal to the wanted one: numbers to 1e-9 (relative; the JSON of a double
    round-trips, this leaves room for a step rounded to whole ticks), anything else exactly."""
    def number(x):
        return isinstance(x, (int, float)) and not isinstance(x, bool)
    if number(recorded) and number(wanted):
        return math.isclose(recorded, wanted, rel_tol=1e-9, abs_tol=1e-300)
    return recorded == wanted


_scene = None


def scene_json():
    """The scene file's JSON object (read once; exit 2 naming it if it is not one)."""
    global _scene
    if _scene is None:
        _scene = json.loads(pathlib.Path(args.scene).read_text())
        require(isinstance(_scene, dict), f"{args.scene}: expected a JSON object (a scene), found {type(_scene).__name__}")
    return _scene


def scene_sha256():
    """The SHA-256 of the scene file's bytes as they are now."""
    return file_sha256(args.scene)


def mismatch(out, summary, scale, sets):
    """Why the usable run in `out` (summary: its summary.json) is not the one this invocation
    would make, as the run recorded it, or None: another scene (summary.json's `scene` against
    the scene file's `name`), or else every difference of
    its scene_as_run.json's simulation.end_time (with --end, or the scene's own end_time),
    simulation.scale and each KEY=VALUE of `sets`, and of summary.json's `threads` (--threads,
    at most this machine's cores, as sph-run runs it). A run without a readable
    scene_as_run.json cannot be checked: that is the reason then."""
    scene = scene_json()
    name = scene.get("name")  # sph-run runs no scene without one
    if summary.get("scene") != name:
        return f"scene {summary.get('scene')!r}, expected {name!r}"
    try:
        kept = json.loads((out / "mode_table.json").read_text())
    except (OSError, ValueError):
        kept = None
    if isinstance(kept, dict) and kept.get("scene_sha256") not in (None, scene_sha256()):
        return "the scene file has changed since (its SHA-256 differs)"
    try:
        ran = read_json_object(out / "scene_as_run.json")
    except Unreadable as e:
        return f"its settings cannot be checked: {e}"
    end = args.end if args.end is not None else scene.get("simulation", {}).get("end_time")
    wanted = ([(["simulation", "end_time"], end)] if end is not None else []) + \
        [(["simulation", "scale"], scale)] + [override(s) for s in sets]
    # A key set twice (--set, then the configuration's own) holds the last value, as sph-run applies them.
    wanted = list({tuple(path): (path, value) for path, value in wanted}.values())
    why = []
    absent = object()
    for path, value in wanted:
        got = ran
        for key in path:
            got = got.get(key, absent) if isinstance(got, dict) else absent
        if got is absent:
            why.append(f"no {'.'.join(path)} in its scene_as_run.json, expected {json.dumps(value)}")
        elif not same(got, value):
            why.append(f"{'.'.join(path)} {json.dumps(got)}, expected {json.dumps(value)}")
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    threads = cores if args.threads <= 0 else min(args.threads, cores or args.threads)
    if summary.get("threads") != threads:
        why.append(f"threads {summary.get('threads')}, expected {threads}")
    return "; ".join(why) or None


def run(tag, scale, sets, rep=0):
    """(summary, None) of a run, or (None, "failed (exit N)" / "interrupted (...)" / "unreadable: <file>: <reason>")."""
    out = out_root / f"scale{scale:g}_{folder(tag)}"
    out = out / f"run{rep}" if args.repeat > 1 else out
    cmd = [args.sph_run, args.scene, "--scale", str(scale), "--threads", str(args.threads), "--no-frames", "-q",
           "--out", str(out)]
    if args.end is not None:
        cmd += ["--end", str(args.end)]
    for s in sets:
        cmd += ["--set", s]
    if args.reuse and (out / "summary.json").exists():
        s, status = read_run(out, numbers=SUMMARY_NUMBERS, keys=("scene",))
        other = None if status else mismatch(out, s, scale, sets)
        if other:
            status = f"another run's ({other})"
        if not status:
            print(f"reusing {out / 'summary.json'}", file=sys.stderr, flush=True)
            s["run_dir"] = str(out)
            return s, None
        print(f"not reusing {out / 'summary.json'}: {status}; running it again", file=sys.stderr, flush=True)
    print(f"[{time.strftime('%H:%M:%S')}] {' '.join(cmd)}", file=sys.stderr, flush=True)
    with contextlib.suppress(OSError):
        (out / "mode_table.json").unlink(missing_ok=True)
    before = scene_sha256()
    s, status = sph_run(cmd, out, numbers=SUMMARY_NUMBERS, keys=("scene",))
    if scene_sha256() == before:  # what --reuse checks the scene file against (not if it changed meanwhile)
        with contextlib.suppress(OSError):
            (out / "mode_table.json").write_text(json.dumps({"scene_sha256": before}) + "\n")
    if status:
        print(f"run {status}: {' '.join(cmd)}\n{log_tail(out)}", file=sys.stderr, flush=True)
    else:
        s["run_dir"] = str(out)
    return s, status


def fronts(s):
    return [f["x"] for f in s.get("front_x_m_at", [])]


def accuracy_series(s):
    """{"front": (t, x, unit), "kinetic energy": (t, E, unit)} of a run (each only if the scene has
    such a probe and the run wrote it), from its probes/ as sph-study reads them; a probe file that
    cannot be parsed leaves its series out (the row's other figures stand)."""
    probes = scene_json().get("probes", [])
    front = [p for p in probes if p.get("type") == "front"][:1]
    fluid = [p for p in probes if p.get("type") == "fluid"][:1]
    out = {}
    for key, probe in (("front", front), ("kinetic energy", fluid)):
        if not probe:
            continue
        try:
            series = primary_series(s["run_dir"], probe)
        except Unreadable:
            continue
        if series:
            out[key] = next(iter(series.values()))
    return out


def rms_against(mine, ref, key):
    """The RMS deviation of series `key` of a run's accuracy_series from the reference's (nan if
    either lacks it)."""
    a, b = mine.get(key), ref.get(key)
    return deviation(a, b)[0] if a is not None and b is not None else float("nan")


def tabulate(sizes):
    """The rows and the Markdown text of every configuration run so far. sizes: per scale,
    (scale, configurations, {name: [summaries]}, {name: [problems]}, {name: status if skipped})."""
    rows, system_tables, notes = [], [], []
    for scale, configs, runs, problems, skipped in sizes:
        med = {name: (statistics.median(r["wall_time_s"] for r in rs), statistics.median(r.get("cpu_time_s", float("nan")) for r in rs))
               for name, rs in runs.items() if rs}
        g = runs["global"][0] if runs.get("global") else None
        ref = accuracy_series(runs["constant"][0]) if runs.get("constant") else {}
        per_step = {}
        for name, rs in runs.items():
            for r in rs:
                for sy in r.get("systems", []):
                    per_step.setdefault(sy["name"], {}).setdefault(name, []).append(1e3 * sy["seconds"] / max(r["steps"], 1))
        extras = [n for n, _ in configs if n not in ("global", "constant", "individual")]
        order = [n for n in ["constant", "global", "individual"] + extras
                 if runs.get(n) or problems.get(n) or n in skipped]
        for name in order:
            rs, probs = runs.get(name, []), problems.get(name, [])
            status = skipped.get(name) or "; ".join(probs) or "ok"
            if probs and rs:
                status = f"{len(rs)} of {len(rs) + len(probs)} runs usable; {status}"
            if status != "ok":
                notes.append(f"* {name}, scale {scale:g}: {status}")
            if not rs:
                rows.append({"scene": pathlib.Path(args.scene).stem, "mode": name, "runs": 0, "status": status})
                continue
            s = rs[0]
            wall, cpu = med[name]
            gf, sf = (fronts(g) if g else []), fronts(s)
            dev = max((abs(a - b) / abs(b) for a, b in zip(sf, gf) if b), default=float("nan"))
            mine = accuracy_series(s)  # each probe file read once per row
            rows.append({
                "scene": s["scene"], "mode": name, "particles": s["fluid_particles"],
                "simulated_s": s["simulated_time_s"], "runs": len(rs), "wall_s": wall, "cpu_s": cpu, "steps": s["steps"],
                "avg_dt_ms": 1e3 * s["avg_dt_s"], "min_dt_ms": 1e3 * s["min_dt_s"], "max_dt_ms": 1e3 * s["max_dt_s"],
                "avg_active_pct": 100 * s["avg_active_fraction"], "max_density_error_pct": 100 * s["max_density_error"],
                "front_t_s": " ".join(f"{f['t']:.2f}" for f in s.get("front_x_m_at", [])),
                "front_x_m": " ".join(f"{x:.3f}" for x in sf), "front_dev_vs_global_pct": 100 * dev,
                "collisions": s["boundary_collisions_total"],
                "speedup_vs_global": med["global"][0] / wall if "global" in med else float("nan"),
                "speedup_vs_global_cpu": med["global"][1] / cpu if "global" in med else float("nan"),
                "speedup_vs_constant": med["constant"][0] / wall if "constant" in med else float("nan"),
                "status": status,
                "evaluations_per_particle": s["steps"] * s["avg_active_fraction"],
                "speedup_times_active": (med["global"][0] / wall if "global" in med else float("nan")) * s["avg_active_fraction"],
                "rms_front_vs_constant_m": rms_against(mine, ref, "front"),
                "rms_kinetic_vs_constant_J": rms_against(mine, ref, "kinetic energy"),
            })
        system_tables.append((scale, order, {sy: {n: statistics.median(v) for n, v in c.items()} for sy, c in per_step.items()}))

    machine = f"{os.cpu_count()} cores, {platform.processor() or platform.machine()}"
    lines = [f"`{pathlib.Path(args.scene).name}`, {args.threads} threads, {machine}, "
             f"{time.strftime('%Y-%m-%d')}; runs one after another, no frames written; "
             f"{args.repeat} run(s) per configuration, interleaved, median times; front deviation is the largest "
             f"|x - x_global| / x_global over the three times; S × f is the wall speed-up over `global` times the "
             f"average active fraction; the RMS deviations are from the `constant` run's probes.", "",
             "| mode | particles | simulated s | wall s | CPU s | steps | avg Δt_sim ms (min–max) | avg active | "
             "evaluations per particle | max ρ error | front x m at t s | front vs global | net catches | "
             "speed-up vs global: wall, CPU (wall vs constant) | S × f | RMS dev front (mm) | RMS dev kinetic energy (J) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]

    def figure(x, form):
        return "–" if math.isnan(x) else format(x, form)
    for r in rows:
        if not r["runs"]:
            lines.append(md_status_row(r["mode"], r["status"], 17))
            continue
        lines.append(f"| {md_cell(r['mode'])} | {r['particles']:,} | {r['simulated_s']:.2f} | {r['wall_s']:.1f} | {r['cpu_s']:.1f} | {r['steps']:,} | "
                     f"{r['avg_dt_ms']:.3f} ({r['min_dt_ms']:.3f}–{r['max_dt_ms']:.3f}) | {r['avg_active_pct']:.0f} % | "
                     f"{r['evaluations_per_particle']:,.0f} | "
                     f"{r['max_density_error_pct']:.1f} % | {r['front_x_m']} at {r['front_t_s']} | {r['front_dev_vs_global_pct']:.1f} % | {r['collisions']} | "
                     f"{r['speedup_vs_global']:.2f}, {r['speedup_vs_global_cpu']:.2f} ({r['speedup_vs_constant']:.2f}) | "
                     f"{figure(r['speedup_times_active'], '.2f')} | {figure(1e3 * r['rms_front_vs_constant_m'], '.2f')} | "
                     f"{figure(r['rms_kinetic_vs_constant_J'], '.3g')} |")
    if notes:
        lines += [""] + notes
    # Where a step's time goes: each system's wall time per step from summary.json (median over the
    # runs of a configuration); a system a configuration does not build shows a dash.
    for scale, order, table in system_tables:
        lines += ["", f"Milliseconds per step by system (scale {scale:g}; median over the runs; `step` is their sum):", "",
                  "| system | " + " | ".join(md_cell(n) for n in order) + " |", "|---|" + "---|" * len(order)]
        for sy, by in table.items():
            lines.append(f"| {sy} | " + " | ".join(f"{by[n]:.2f}" if n in by else "–" for n in order) + " |")
        lines.append("| **step** | " + " | ".join(f"**{sum(by.get(n, 0.0) for by in table.values()):.2f}**" for n in order) + " |")
    return rows, "\n".join(lines) + "\n"


COLUMNS = ["scene", "mode", "particles", "simulated_s", "runs", "wall_s", "cpu_s", "steps", "avg_dt_ms", "min_dt_ms",
           "max_dt_ms", "avg_active_pct", "max_density_error_pct", "front_t_s", "front_x_m", "front_dev_vs_global_pct",
           "collisions", "speedup_vs_global", "speedup_vs_global_cpu", "speedup_vs_constant", "status",
           "evaluations_per_particle", "speedup_times_active", "rms_front_vs_constant_m", "rms_kinetic_vs_constant_J"]


def write_tables(sizes):
    rows, text = tabulate(sizes)
    write_atomic(out_root / "mode_table.md", text)
    write_atomic(out_root / "mode_table.csv", csv_text(rows, COLUMNS))
    return text


sizes = []
for scale in SCALES:
    configs = [("global", args.set + ["simulation.stepping.mode=global"])]
    runs, problems, skipped = {}, {}, {}
    sizes.append((scale, configs, runs, problems, skipped))

    def record(name, result):
        s, problem = result
        if s:
            runs.setdefault(name, []).append(s)
        else:
            problems.setdefault(name, []).append(problem)
        write_tables(sizes)

    # The first global run also fixes the constant step (its smallest step).
    result = run("global", scale, configs[0][1], 0)
    first = result[0]
    record("global", result)
    if not args.no_constant:
        configs.append(("constant", args.set + ["simulation.stepping.mode=constant"] +
                        ([f"simulation.stepping.dt={first['min_dt_s']!r}"] if first else [])))
        if not first:
            skipped["constant"] = "skipped: its step is the first global run's smallest, and that run is not usable"
    configs.append(("individual", args.set + ["simulation.stepping.mode=individual"]))
    configs += [(name, args.set + sets) for name, sets in EXTRAS]
    for rep in range(args.repeat):
        for name, sets in configs:
            if (name == "global" and rep == 0) or name in skipped:
                continue
            record(name, run(name, scale, sets, rep))

text = write_tables(sizes)
print(text)
exit_if_unusable([f"scale {scale:g} {name}: {p}" for scale, _, _, problems, _ in sizes for name, ps in problems.items()
                  for p in ps], f"{out_root / 'mode_table.md'} and mode_table.csv")
