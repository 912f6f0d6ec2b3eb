#!/usr/bin/env python3
"""Compares two trees of sph-run outputs (one directory per run) for identical physics.

usage: tools/compare_runs.py BEFORE_DIR AFTER_DIR

Per run directory: every file under frames/ and probes/ byte for byte; stats.csv column by
column for the physics columns (all but wall_s and the ms_<system> timings, which are
measurements of the machine, not of the flow), matched by name; summary.json key by key
except timings, memory and the per-system table. Prints one line per run and exits 1 if any
run differs (or exists on one side only).
"""
import json
import pathlib
import sys
from sph_python import errors_as_exit_2, usage_unless  # noqa: E402 (tools/ is the script's folder)

errors_as_exit_2()

TIMING_KEYS = {"wall_time_s", "cpu_time_s", "fluid_particle_steps_per_s", "peak_memory_bytes",
               "particle_data_bytes", "bytes_per_fluid_particle", "peak_memory_per_fluid_particle",
               "systems", "systems_total_s", "spatial_sort_s", "threads"}


def stats_columns(path):
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    keep = [i for i, name in enumerate(header) if name != "wall_s" and not name.startswith("ms_")]
    cols = {header[i]: [row.split(",")[i] for row in lines[1:]] for i in keep}
    return cols


def compare_run(a, b):
    diffs = []
    for sub in ("frames", "probes"):
        fa = sorted(p.relative_to(a) for p in (a / sub).rglob("*") if p.is_file()) if (a / sub).is_dir() else []
        fb = sorted(p.relative_to(b) for p in (b / sub).rglob("*") if p.is_file()) if (b / sub).is_dir() else []
        if fa != fb:
            diffs.append(f"{sub}/: file lists differ ({len(fa)} vs {len(fb)})")
            continue
        for rel in fa:
            if (a / rel).read_bytes() != (b / rel).read_bytes():
                diffs.append(f"{rel} differs")
    files = [f for f in ("frames", "probes") if (a / f).is_dir()]
    if (a / "stats.csv").exists() != (b / "stats.csv").exists():
        diffs.append("stats.csv on one side only")
    elif (a / "stats.csv").exists():
        ca, cb = stats_columns(a / "stats.csv"), stats_columns(b / "stats.csv")
        for name in ca:
            if name not in cb:
                diffs.append(f"stats.csv: column {name} missing after")
            elif ca[name] != cb[name]:
                first = next(i for i, (x, y) in enumerate(zip(ca[name], cb[name])) if x != y) \
                    if len(ca[name]) == len(cb[name]) else min(len(ca[name]), len(cb[name]))
                diffs.append(f"stats.csv: column {name} differs from row {first + 1}")
        for name in cb:
            if name not in ca:
                diffs.append(f"stats.csv: column {name} new after (not compared)")
    if (a / "summary.json").exists() != (b / "summary.json").exists():
        diffs.append("summary.json on one side only")
    elif (a / "summary.json").exists():
        sa = json.loads((a / "summary.json").read_text())
        sb = json.loads((b / "summary.json").read_text())
        for k in sorted(set(sa) | set(sb)):
            if k in TIMING_KEYS:
                continue
            if sa.get(k) != sb.get(k):
                diffs.append(f"summary.json: {k}: {sa.get(k)!r} vs {sb.get(k)!r}")
    return diffs, files


def main():
    usage_unless(2, __doc__)
    before, after = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    for d in (before, after):
        if not d.is_dir():
            print(f"compare_runs.py: {d}: not a folder of runs", file=sys.stderr)
            sys.exit(2)
        if (d / "summary.json").exists() or (d / "stats.csv").exists():
            print(f"compare_runs.py: {d}: a run's own folder; give the folders that hold the runs "
                  f"(one sub-folder per run, as tools/check_identical.sh writes them)", file=sys.stderr)
            sys.exit(2)
    runs = sorted({p.name for p in before.iterdir() if p.is_dir()} | {p.name for p in after.iterdir() if p.is_dir()})
    if not runs:
        print(f"compare_runs.py: {before} and {after} hold no run folders", file=sys.stderr)
        sys.exit(2)
    bad = 0
    frames = 0
    for name in runs:
        a, b = before / name, after / name
        if not a.is_dir() or not b.is_dir():
            print(f"DIFF  {name}: on one side only")
            bad += 1
            continue
        diffs, _ = compare_run(a, b)
        # a new, uncompared column is a note, not a difference
        real = [d for d in diffs if "not compared" not in d]
        n = len(list((a / "frames").glob("*"))) if (a / "frames").is_dir() else 0
        frames += n
        steps = max(0, len((a / "stats.csv").read_text().splitlines()) - 1) if (a / "stats.csv").exists() else 0
        status = "DIFF" if real else "same"
        print(f"{status}  {name}: {steps} steps, {n} frame files" + ("" if not diffs else "; " + "; ".join(diffs[:4])))
        bad += bool(real)
    print(f"{len(runs) - bad} of {len(runs)} runs identical ({frames} frame files compared byte for byte)")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
