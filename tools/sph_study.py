#!/usr/bin/python3
"""sph-study: the speed/accuracy trade of one scene, measured.

usage: sph-study SCENE.json [--config "MODE [--set KEY=VALUE ...] [--name LABEL]" ...]
                 [--no-default-modes] [--end T] [--scale S] [--set KEY=VALUE ...] [--threads 2]
                 [--reference DIR | --reference-dt DT] [--out out/study/<scene>] [--sph-run PATH]

Runs a list of configurations of one scene with sph-run, one after another (never in
parallel, so that wall times compare), and writes into --out:

  study.md, study.csv   He et al. Table 1 / Ihmsen et al. Table 1 with accuracy columns:
                        method and mode; particles and simulated time; wall time, steps,
                        average/minimum/maximum dt; average active %; speed-up over `global` and
                        over `constant`; average and maximum density error; RMS deviation from a
                        reference run of every probe series and of the kinetic energy; error
                        against the experiment for probes that declare one. For WCSPH runs with
                        the acoustic condition, the evaluations per particle at the sound-crossing
                        bound (tools/stepping_bound.py), and under the table for `global` and
                        `constant` by how much per-particle stepping could at most undercut them.
  pareto.png            wall time against error, one point per configuration, the front of
                        non-dominated configurations joined and marked.
  dt.png                dt_sim (log) and active fraction over time of every run, overlaid
                        (tools/plot_dt.py: He et al. Fig. 2; Ihmsen et al. Fig. 4).
  <run>/                every run's outputs (stats.csv, summary.json, probes/, run.log).
  <stem>.study.json     for a scene without a fluid probe, the scene the runs read: a copy with
                        one added (`study_fluid`: the kinetic energy is always compared) and its
                        relative files (a mesh's OBJ, an experiment's CSV) made absolute from the
                        scene's folder. The scene file itself is never written, also when --out
                        is its folder.

When. study.md and study.csv are rewritten after every run (into a temporary file in --out, then
renamed onto the table: never half-written), so a study that is interrupted or crashes leaves the
rows of every run it finished; until the reference has run their accuracy columns are empty and
the column "accuracy note" says "pending: ...". pareto.png and dt.png are drawn at the end.

Failures. A run sph-run reports failed is a row "failed (exit N)"; a run sph-run stopped by a
signal (summary.json marked "interrupted") a row "interrupted (<signal> at t = T s)"; a run whose
summary.json, stats.csv or probe files cannot be read (missing, truncated, not JSON or CSV) a row
"unreadable: <file>: <reason>"; a `constant` configuration whose step source is not usable (see
Configurations) a row "skipped: <why>". If the reference run fails or cannot be read, every row
keeps its cost columns, the accuracy columns are empty, "accuracy note" says "unavailable:
<reason>" and there is no pareto.png. Exit codes: 0 the tables are complete ("failed" and
"skipped" rows included); 2 bad arguments, before any run and before anything is written, or,
after writing the tables, a run unreadable or interrupted, or the reference unavailable (one
line, `sph-study: error: ...`); 130 / 143 interrupted (Ctrl-C / SIGTERM: the running sph-run, in
a session of its own so that a terminal's Ctrl-C reaches the study only, gets one SIGTERM, and
SIGKILL after 10 s; it finishes its step and writes its outputs, summary.json marked
"interrupted"; the study waits for it and dies by that signal), the tables holding the runs
finished before.

Configurations. By default every `method mode` pair the scene loads with (sph-run
--list-modes), so a mode added to the engine joins the study with no change here; --config adds
more (MODE is `mode` or `method/mode`; --set keys may drop the leading `simulation.`, e.g.
`--config "individual --set stepping.lambda_v=0.1"`). A `constant` configuration without its
own `stepping.dt` takes the smallest step an adaptive run of the same method took (the largest
fixed step known to be stable for the whole run, as a user without adaptivity would choose it):
the plain `global` run's if the study has one, else the smallest over the method's adaptive runs.
If that run (or every such run) is not usable, the configuration is skipped, a row saying why;
with no adaptive run of its method in the study it runs at the scene's own step (noted under the
table).

Reference. A `constant` run of the scene's method at a small step: half the smallest step the
`global` run took (or --reference-dt), or an earlier run given with --reference DIR.
Deviation of a series = RMS over the reference's sample times of (run - reference), the run
interpolated linearly in time. The "error" of the Pareto plot is the mean over the series
(probe primary columns and kinetic energy) of that RMS divided by the reference series' range
(max - min): a dimensionless 0..1 figure, 0 for the reference itself.

Experiment. A probe with an `experiment` object (scenes/README.md) is compared as
T = t * t_scale, Z = (value - value_offset) * value_scale against the file's first two
columns (after '#' comment lines and a header); RMS relative error over t_range, minimised over
one time shift |dT| <= max_shift (a lab gate does not open instantly).
"""
import argparse
import datetime
import json
import math
import os
import pathlib
import platform
import resource
import shlex
import subprocess
import sys
import time

# sph_python.py sits beside this file (tools/, or build/tools/ beside sph-study); put that folder
# first on the path so that loading this file as a module (tools that import it, the tests) finds it too.
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from sph_python import Unreadable, csv_text, errors_as_exit_2, exit_if_unusable, fail, md_cell, md_status_row, need, \
    read_csv_columns, read_json_object, write_atomic  # noqa: E402
import sph_python  # noqa: E402
import stepping_bound  # noqa: E402

need("numpy")
import numpy as np  # noqa: E402

TOP_KEYS = {"name", "description", "simulation", "domain", "fluid", "fluid_blocks", "boundaries", "output",
            "pcisph", "dfsph", "boundary", "emitters", "probes", "standing_wave"}  # engine/data/scene_detail.hpp k_top_keys
HERE = pathlib.Path(__file__).resolve().parent


def full_key(key):
    """`stepping.lambda_v` -> `simulation.stepping.lambda_v`; scene top-level keys unchanged."""
    head = key.split(".", 1)[0].lstrip("/")
    return key if head in TOP_KEYS else "simulation." + key


def parse_config(spec):
    try:
        words = shlex.split(spec)
    except ValueError as e:  # an unclosed quote
        fail(f"--config {spec!r}: {e}")
    if not words:
        fail(f"--config {spec!r}: empty (expected 'MODE [--set KEY=VALUE ...] [--name LABEL]')")
    mode, rest = words[0], words[1:]
    method = None
    if "/" in mode:
        method, mode = mode.split("/", 1)
    sets, name = [], None
    i = 0
    while i < len(rest):
        if rest[i] == "--set" and i + 1 < len(rest):
            k, eq, v = rest[i + 1].partition("=")
            if not eq:
                fail(f"--config {spec!r}: {rest[i + 1]!r} is not KEY=VALUE")
            sets.append(f"{full_key(k.strip())}={v.strip()}")
            i += 2
        elif rest[i] == "--name" and i + 1 < len(rest):
            name = rest[i + 1]
            i += 2
        else:
            fail(f"--config {spec!r}: unexpected {rest[i]!r} (expected --set KEY=VALUE or --name LABEL)")
    label = name or " ".join([f"{method}/{mode}" if method else mode] + [s.split("=", 1)[0].split(".")[-1] + "=" +
                                                                          s.split("=", 1)[1] for s in sets])
    return {"label": label, "method": method, "mode": mode, "sets": sets}


def read_csv(path, columns=(), min_rows=0, final_newline=True):
    """Numeric CSV with a header; '#' lines skipped. Returns {column: np.array}; Unreadable naming
    the file and the line as sph_python.read_csv_columns (a truncated row, a missing column)."""
    return {h: np.array(v, dtype=float) for h, v in read_csv_columns(path, columns, min_rows, final_newline).items()}


def fluid_time_average(t, dt, value, whole_fluid):
    """Time average of a per-step fluid average from stats.csv (t the step's end, dt its length):
    each step whose figures cover every fluid row (`whole_fluid` 1) holds until the next such
    step begins; `binned`'s steps over the due rows only are left out, their average is not the
    fluid's. With every step whole (every mode but `binned`; rows of a rollback included, as
    before), each step weighted by its dt."""
    if np.all(whole_fluid > 0):
        return float(np.sum(value * dt) / np.sum(dt))
    keep = np.flatnonzero(whole_fluid > 0)
    if len(keep) == 0:
        return float("nan")
    start = t[keep] - dt[keep]
    until = np.append(start[1:], t[-1])
    weight = until - start
    return float(np.sum(value[keep] * weight) / np.sum(weight))


def read_experiments(scene_path, probes):
    """The measured data of every probe with an `experiment` object, {probe name: (te, ze)}: the
    first two columns of its file (scenes/README.md; a column `a_in` is left out), relative to the
    scene's folder. sph-study and resolution_study read them once, before any run, so that a
    probe without a file, or a file that is missing, unreadable, not numeric CSV, with fewer than
    two columns or no row, ends the tool at once (exit 2, naming the scene, the probe and the
    file) instead of after every run."""
    scene_dir = pathlib.Path(scene_path).resolve().parent
    measured = {}
    for probe in probes:
        if "experiment" not in probe:
            continue
        e = probe["experiment"]
        what = f"{scene_path}: probe '{probe.get('name')}'"
        if not isinstance(e, dict) or not isinstance(e.get("file"), str):
            fail(f'{what}: experiment without a "file"')
        try:
            data = read_csv(scene_dir / e["file"], final_newline=False)  # a file people write
        except Unreadable as error:
            fail(f"{what}: experiment file {error}")
        keys = [k for k in data if k != "a_in"]
        if len(keys) < 2 or len(data[keys[0]]) == 0:
            fail(f"{what}: experiment file {scene_dir / e['file']}: expected a header and at least one row of two "
                 f"or more columns, found {len(keys)} column(s) and {len(data[keys[0]]) if keys else 0} row(s)")
        measured[probe.get("name")] = (data[keys[0]], data[keys[1]])
    return measured


# What the tables read from a run's summary.json: a summary without one of them is unreadable.
SUMMARY_NUMBERS = ("steps", "wall_time_s", "fluid_particles", "simulated_time_s", "avg_dt_s", "min_dt_s",
                   "max_dt_s", "avg_active_fraction", "max_density_error")


def machine():
    model = platform.processor() or platform.machine()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} cores, {model}"


def source_commit():
    try:
        return subprocess.run(["git", "-C", str(HERE), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


class Study:
    def __init__(self, args):
        """Reads the scene and the arguments; writes nothing (write_scene does, once every
        argument is checked)."""
        self.a = args
        self.scene = pathlib.Path(args.scene)
        if not self.scene.is_file():
            fail(f"{self.scene}: no such scene file")
        try:
            self.scene_json = json.loads(self.scene.read_text())
        except (OSError, ValueError) as e:
            fail(f"{self.scene}: not a readable JSON scene ({e})")
        if not isinstance(self.scene_json, dict):
            fail(f"{self.scene}: expected a JSON object (a scene), found {type(self.scene_json).__name__}")
        self.out = pathlib.Path(args.out or f"out/study/{self.scene_json.get('name', self.scene.stem)}")
        self.common = [full_key(s) for s in args.set]
        if args.end is not None:
            self.common.append(f"simulation.end_time={args.end!r}")
        if args.scale is not None:
            self.common.append(f"simulation.scale={args.scale!r}")
        self.common.append("simulation.frame_rate=0")  # no particle frames: timings are of the physics
        self.probes = self.scene_json.get("probes", [])
        self.fluid_probe = next((p.get("name", f"fluid_{i}") for i, p in enumerate(self.probes)
                                 if p.get("type") == "fluid"), None)
        self.scene_path = self.scene  # the scene the runs read: this one, or write_scene's copy
        self.copy_json = None
        if self.fluid_probe is None:  # kinetic energy is always compared: add a whole-fluid probe
            self.scene_json.setdefault("probes", []).append({"type": "fluid", "name": "study_fluid", "rate": 100})
            self.copy_json = sph_python.scene_copy(self.scene_json, self.scene)
            self.fluid_probe = "study_fluid"
            self.probes = self.scene_json["probes"]
        for i, probe in enumerate(self.probes):  # the engine's default name, <type>_<index>
            probe.setdefault("name", f"{probe.get('type')}_{i}")
        self.measured = {}  # {probe name: (te, ze)}, read_experiments before any run
        self.configs, self.results, self.problems, self.done = [], [], [], []
        self.ref_summary = self.ref_series = None
        self.ref_note = "pending: the reference runs after the configurations"  # None once it is read
        self.started = datetime.datetime.now()
        self.context = f"{args.threads} threads, {machine()}, {self.started:%Y-%m-%d %H:%M}, engine {source_commit()}"

    def write_scene(self):
        """The runs' scene: with a fluid probe added (__init__), the copy <stem>.study.json in
        --out, its relative files absolute (sph_python.scene_copy). Never the scene itself: a
        copy path that is the scene (a link to it in --out) is refused, exit 2."""
        if self.copy_json is None:
            return
        copy = self.out / f"{self.scene.stem}.study.json"
        if copy.resolve() == self.scene.resolve():
            fail(f"--out {self.out}: its {copy.name} is the scene {self.scene} itself (a link to it?), where the study "
                 f"would write its copy of the scene: give another --out")
        write_atomic(copy, json.dumps(self.copy_json, indent=2) + "\n")
        self.scene_path = copy

    def sph_run(self, extra, out_dir, label, index, total, then=None):
        """One run (sph_python.sph_run; its output into out_dir/run.log, progress lines echoed):
        (summary, None), the summary with its own figures from `then` if given, or (None, status)."""
        cmd = [self.a.sph_run, str(self.scene_path), "--threads", str(self.a.threads), "--out", str(out_dir)]
        for s in self.common + extra:
            cmd += ["--set", s]
        print(f"[{time.strftime('%H:%M:%S')}] run {index}/{total} {label}: {shlex.join(cmd)}", flush=True)
        t0 = time.time()
        cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)

        def echo(line):
            if " t = " in line or "error" in line or "failed" in line:
                print(f"    {label}: {line.split('] ', 2)[-1].strip()}", flush=True)

        def read(s):
            cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            # whole process, set-up included: less sensitive than wall time to a shared machine
            s["_cpu_s"] = (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime)
            s["_dir"] = str(out_dir)
            if then:
                then(s)
            return s

        s, status = sph_python.sph_run(cmd, out_dir, numbers=SUMMARY_NUMBERS, then=read, echo=echo)
        if status:
            print(f"    {label}: {status}; see {out_dir / 'run.log'}", flush=True)
            return None, status
        print(f"    {label}: {s['steps']} steps, {s['wall_time_s']:.1f} s wall ({time.time() - t0:.1f} s with set-up)",
              flush=True)
        return s, None

    def list_modes(self):
        """The "method mode" pairs the scene loads with (asked of sph-run once, then kept; of the
        scene itself, before write_scene, as the added probe changes no mode)."""
        if getattr(self, "_modes", None) is not None:
            return self._modes
        proc = subprocess.run([self.a.sph_run, str(self.scene), "--list-modes", "-q"] +
                              sum((["--set", s] for s in self.common), []), capture_output=True, text=True)
        if proc.returncode != 0:
            fail(f"sph-run --list-modes failed: {proc.stderr.strip()}")
        self._modes = [line.split() for line in proc.stdout.splitlines() if len(line.split()) == 2 and line[0] != "["]
        return self._modes

    def configurations(self):
        """Every configuration to run (the scene's modes unless --no-default-modes, then each
        --config); exit 2 if there is none. main asks before anything is written."""
        configs = []
        if not self.a.no_default_modes:
            for method, mode in self.list_modes():
                configs.append({"label": mode if method == self.scene_method() else f"{method}/{mode}",
                                "method": method, "mode": mode, "sets": []})
        configs += [parse_config(c) for c in self.a.config]
        if not configs:
            fail("no configurations (--no-default-modes without --config)")
        for c in configs:
            c["method"] = c["method"] or self.scene_method()
        return configs

    def scene_method(self):
        return self.scene_json.get("simulation", {}).get("method", "wcsph")

    def own_figures(self, r):
        """A finished run's figures that need no other run: cost, experiment error, the
        sound-crossing bound, the standing wave, and its series for the deviation from the
        reference. Unreadable if its stats.csv or a probe file is missing or cannot be parsed."""
        d = pathlib.Path(r["_dir"])
        stats = read_csv(d / "stats.csv", columns=("t", "dt", "rho_err_avg", "whole_fluid"), min_rows=1)
        dt = stats["dt"]
        cost = {
            "status": "ok", "particles": r["fluid_particles"], "simulated_s": r["simulated_time_s"],
            "wall_s": r["wall_time_s"], "cpu_s": r["_cpu_s"], "steps": r["steps"], "avg_dt_ms": 1e3 * r["avg_dt_s"],
            "min_dt_ms": 1e3 * r["min_dt_s"], "max_dt_ms": 1e3 * r["max_dt_s"],
            "avg_active_pct": 100 * r["avg_active_fraction"],
            "speedup_vs_global": None, "speedup_vs_constant": None,  # set when the table is written
            # time average over the run of the fluid's average, and the maximum
            "avg_density_error_pct": 100 * fluid_time_average(stats["t"], dt, stats["rho_err_avg"], stats["whole_fluid"]),
            "max_density_error_pct": 100 * r["max_density_error"],
            # the safety net's corrections over the run, and those of particles with no fluid
            # neighbour (lone droplets, whose wall contact the net is by design; WCSPH only)
            "net_catches": r.get("boundary_collisions_total", 0),
            "droplet_contacts": r.get("droplet_contacts_total"),
        }
        series = primary_series(d, self.probes, strict=True)
        after = {}
        for p in (p for p in self.probes if "experiment" in p):
            err, shift, at_bound = experiment_error(d, p, self.measured[p["name"]])
            after[f"exp err {p['name']} %"] = 100 * err
            after[f"exp shift {p['name']}"] = shift
            after[f"exp shift at bound {p['name']}"] = at_bound
        # What per-particle stepping could at most gain over this run at its lambda_c
        # (tools/stepping_bound.py): WCSPH with the acoustic condition only.
        try:
            b = stepping_bound.bound(d)
            after["evaluations per particle"] = b["evaluations_per_particle"]
            after["evaluations per particle at the sound-crossing bound"] = b["bound_evaluations_per_particle"]
            after["evaluations / sound-crossing bound"] = b["ratio"]
        except stepping_bound.BadInput:
            pass
        wave = wave_figures(d, self.fluid_probe, r, self.scene_json)
        if wave:
            after["wave period s"] = wave["period_s"]
            after["wave period err %"] = 100 * (wave["period_s"] / wave["period_theory_s"] - 1)
            after["wave decay 1/s"] = wave["decay_per_s"]
            after["wave decay / theory"] = wave["decay_per_s"] / wave["decay_theory_per_s"] \
                if wave["decay_theory_per_s"] > 0 else float("nan")
            after["wave theory"] = f"T {wave['period_theory_s']:.4f} s, decay {wave['decay_theory_per_s']:.4g} 1/s"
        return {"cost": cost, "series": series, "after": after}

    def rows(self):
        """One row per configuration run so far, in the configurations' order."""
        def wall_of(mode):
            for r, c in zip(self.results, self.configs):
                if r and c["mode"] == mode and not c["sets"] and c["method"] == self.scene_method():
                    return r["wall_time_s"]
            return None

        w_global, w_constant = wall_of("global"), wall_of("constant")
        rows = []
        for c, r, problem, done in zip(self.configs, self.results, self.problems, self.done):
            if not done:
                continue
            row = {"configuration": c["label"], "method": c["method"], "mode": c["mode"]}
            if not r:
                row["status"] = problem
                rows.append(row)
                continue
            row.update(r["_own"]["cost"])
            row["speedup_vs_global"] = w_global / r["wall_time_s"] if w_global else float("nan")
            row["speedup_vs_constant"] = w_constant / r["wall_time_s"] if w_constant else float("nan")
            if self.ref_series is not None:
                mine, rel = r["_own"]["series"], []
                for name, series in self.ref_series.items():
                    if name in mine:
                        rms, relative = deviation(mine[name], series)
                        row[f"dev {name} ({series[2]})"] = rms
                        rel.append(relative)
                # Over the series whose reference varies (a flat reference has no range to divide by).
                rel = [x for x in rel if np.isfinite(x)]
                row["deviation (mean rel.)"] = float(np.mean(rel)) if rel else float("nan")
            else:  # pending or unavailable: every series the reference would give, empty, and why not
                for i, p in enumerate(self.probes):
                    name, _, unit = series_of(p, i)
                    row[f"dev {name} ({unit})"] = None
                row["deviation (mean rel.)"] = None
            row["accuracy note"] = self.ref_note or ""
            row.update(r["_own"]["after"])
            rows.append(row)
        return rows

    def write_tables(self):
        """study.csv and study.md of the runs so far, each replaced atomically; returns (rows, md text)."""
        rows = self.rows()
        columns = []
        for row in rows:
            for k in row:
                if k not in columns:
                    columns.append(k)
        write_atomic(self.out / "study.csv", csv_text(rows, columns))
        text = self.markdown(rows, columns)
        write_atomic(self.out / "study.md", text)
        return rows, text

    def markdown(self, rows, columns):
        dev_cols = [k for k in columns if k.startswith("dev ")]
        exp_cols = [k for k in columns if k.startswith("exp err ")]
        if self.ref_note is None:
            s = self.ref_summary
            ref = (f"Reference: constant, Δt = {1e3 * s['avg_dt_s']:.4g} ms, {s['steps']:,} steps, "
                   f"{s['wall_time_s']:.1f} s wall.")
        else:
            ref = f"Reference: {self.ref_note}."
        left = sum(not d for d in self.done)
        head = (f"`{self.scene.name}` ({self.configs and self.scene_method()}), {self.context}; runs one after another, "
                f"no frames. {ref}" + (f" Partial: {left} of {len(self.configs)} configurations still to run." if left else ""))
        hdr = ["configuration", "particles", "sim s", "wall s", "CPU s", "steps", "Δt ms avg (min–max)", "active %",
               "speed-up vs global", "vs constant", "ρ err avg / max %", "net catches (droplets)"] + \
              [k.replace("dev ", "RMS dev ") for k in dev_cols] + ["dev (mean rel.)"] + \
              [k.replace("exp err ", "exp. err ") + " (ΔT)" for k in exp_cols]
        wave_cols = "wave period s" in columns
        if wave_cols:
            hdr += ["wave period s (err %)", "decay 1/s (× theory)"]
        lines = [head, "", "| " + " | ".join(hdr) + " |", "|" + "---|" * len(hdr)]

        def acc(x):  # an accuracy cell: a number, or "pending"/"unavailable" (the reason is in the head line)
            return self.ref_note.split(":")[0] if x is None and self.ref_note else fmt(x)

        for row in rows:
            if row["status"] != "ok":
                lines.append(md_status_row(row["configuration"], row["status"], len(hdr)))
                continue
            cells = [md_cell(row["configuration"]), f"{row['particles']:,}", f"{row['simulated_s']:.3g}", f"{row['wall_s']:.1f}",
                     f"{row['cpu_s']:.1f}", f"{row['steps']:,}", f"{row['avg_dt_ms']:.3g} ({row['min_dt_ms']:.3g}–{row['max_dt_ms']:.3g})",
                     f"{row['avg_active_pct']:.0f}", fmt(row["speedup_vs_global"]), fmt(row["speedup_vs_constant"]),
                     f"{row['avg_density_error_pct']:.2f} / {row['max_density_error_pct']:.1f}",
                     f"{row['net_catches']:,}" + (f" ({row['droplet_contacts']:,})" if row["droplet_contacts"] is not None else "")]
            cells += [acc(row.get(k)) for k in dev_cols] + [acc(row["deviation (mean rel.)"])]
            cells += [f"{row[k]:.1f} ({row[k.replace('exp err ', 'exp shift ').replace(' %', '')]:+.2f}"
                      + ("*" if row.get(k.replace("exp err ", "exp shift at bound ").replace(" %", "")) else "") + ")"
                      for k in exp_cols]
            if wave_cols:
                cells += [f"{row['wave period s']:.4f} ({row['wave period err %']:+.2f})" if "wave period s" in row else "",
                          f"{row['wave decay 1/s']:.4f} ({row['wave decay / theory']:.2f})" if "wave period s" in row else ""]
            lines.append("| " + " | ".join(cells) + " |")
        notes = [f"* {md_cell(c['label'])}: {c['note']}" for c in self.configs if c.get("note")]
        if any(v is True for row in rows for k, v in row.items() if k.startswith("exp shift at bound ")):
            notes.append("* ΔT marked * is the first or last shift the search could try (±max_shift, or where the run "
                         "ends): a better fit may lie beyond it, with a wider `max_shift` or a longer run.")
        for row in rows:
            if row["status"] == "ok" and row["mode"] in ("global", "constant") and \
                    "evaluations / sound-crossing bound" in row:
                notes.append(f"* {row['configuration']}: per-particle stepping at the same λc could evaluate at most "
                             f"{row['evaluations / sound-crossing bound']:.2f}× less than this run (its "
                             f"{row['evaluations per particle']:,.0f} evaluations per particle against "
                             f"{row['evaluations per particle at the sound-crossing bound']:,.0f} at the sound-crossing "
                             f"bound; tools/stepping_bound.py)")
        theory = next((row["wave theory"] for row in rows if "wave theory" in row), None)
        if theory:
            notes.append(f"* standing wave, linear theory: {theory} (ν of the first run; each row's ratio uses its own); measured from the fluid "
                         f"probe's centre_x after the wave is given")
        return "\n".join(lines + ([""] + notes if notes else [])) + "\n"

    def run(self):
        """Every configuration, then the reference; the tables are rewritten after each run."""
        configs = self.configs = self.configs or self.configurations()
        # Adaptive runs first: a `constant` configuration takes its step from them.
        order = sorted(range(len(configs)), key=lambda k: configs[k]["mode"] == "constant")
        results = self.results = [None] * len(configs)
        self.problems = [None] * len(configs)  # a status ("failed (exit N)", "unreadable: ...", ...) or None
        self.done = [False] * len(configs)
        total = len(configs) + (0 if self.a.reference else 1)
        for n, k in enumerate(order, 1):
            c = configs[k]
            sets = [f"simulation.method={c['method']}", f"simulation.stepping.mode={c['mode']}"] + c["sets"]
            if c["mode"] == "constant" and not any(s.startswith("simulation.stepping.dt=") for s in c["sets"]):
                # the plain `global` run's smallest step (a global stability bound); an
                # individual run's smallest dt_sim is one particle's and would be too strict
                adaptive = [j for j, cc in enumerate(configs) if cc["mode"] != "constant" and cc["method"] == c["method"]]
                glob = [j for j in adaptive if configs[j]["mode"] == "global" and not configs[j]["sets"]]
                source = glob or adaptive
                pool = [results[j] for j in source if results[j]]
                which = "global" if glob else "adaptive"
                if pool:
                    dt = min(r["min_dt_s"] for r in pool)
                    sets.append(f"simulation.stepping.dt={dt!r}")
                    c["note"] = f"dt = {dt * 1e3:.4g} ms, the smallest step of the {which} run"
                elif source:  # as mode_table: no step known to be stable, so no run
                    why = "; ".join(f"{configs[j]['label']}: {self.problems[j]}" for j in source)
                    self.problems[k] = (f"skipped: its step is the smallest the {which} run of {c['method']} took, "
                                        f"and no such run is usable ({why})")
                    print(f"    {c['label']}: {self.problems[k]}", flush=True)
                    self.done[k] = True
                    self.write_tables()
                    continue
                else:
                    c["note"] = f"dt = the scene's own: the study has no adaptive run of {c['method']} to take it from"
            slug = "".join(ch if ch.isalnum() or ch in "._-" else "_" for ch in c["label"])
            # the run's own figures, read now: a file it lacks makes its row, not the study, fail
            r, problem = self.sph_run(sets, self.out / f"{n:02d}_{slug}", c["label"], n, total,
                                      then=lambda s: s.__setitem__("_own", self.own_figures(s)))
            results[k], self.problems[k], self.done[k] = r, problem, True
            self.write_tables()
        self.reference(total)
        return self.write_tables()

    def load_reference(self, d, what, strict):
        """Reads the reference's summary and series; returns None, or the reason they are
        unavailable. `strict`: a run of this scene, whose every probe file must be there."""
        try:
            summary = read_json_object(d / "summary.json", numbers=("avg_dt_s", "steps", "wall_time_s"))
            series = primary_series(d, self.probes, strict)
        except Unreadable as e:
            return f"{what} cannot be read: {e}"
        self.ref_summary, self.ref_series = summary, series
        return None

    def reference(self, total):
        """Sets self.ref_series and ref_summary, or self.ref_note to why they are unavailable."""
        if self.a.reference:
            return  # loaded (and checked) before the first run
        dt = self.a.reference_dt
        if dt is None:
            glob = [r for r, c in zip(self.results, self.configs) if r and c["mode"] == "global" and not c["sets"]]
            pool = glob or [r for r in self.results if r]
            if not pool:
                self.ref_note = ("unavailable: no run finished, so no step to derive the reference's from "
                                 "(give --reference-dt)")
                return
            dt = 0.5 * min(r["min_dt_s"] for r in pool)
        d = self.out / "reference"
        s, problem = self.sph_run([f"simulation.method={self.scene_method()}", "simulation.stepping.mode=constant",
                                   f"simulation.stepping.dt={dt!r}"], d, f"reference (constant, dt = {dt * 1e3:.4g} ms)",
                                  total, total)
        if problem:
            self.ref_note = (f"unavailable: the reference run's output is {problem}" if problem.startswith("unreadable")
                             else f"unavailable: the reference run {problem}, see {d / 'run.log'}")
            return
        why = self.load_reference(d, "the reference run's output", strict=True)
        self.ref_note = f"unavailable: {why}" if why else None


# ---- accuracy ----

def series_of(probe, i):
    """(series name, column, unit) of a probe's primary column; a fluid probe's is the kinetic energy."""
    name = probe.get("name", f"{probe['type']}_{i}")
    return {"fluid": ("kinetic energy", "kinetic", "J"), "pressure": (name, "p", "Pa"),
            "height": (name, "height", "m")}.get(probe["type"], (name, "front", "m"))


def primary_series(run_dir, probes, strict=False):
    """{series name: (t, values, unit)}: each probe's primary column, and the kinetic energy.
    A probe file that is not there is left out, or with `strict` (a run of this scene, which
    writes every probe) Unreadable; one that cannot be parsed is Unreadable."""
    out = {}
    for i, p in enumerate(probes):
        key, col, unit = series_of(p, i)
        name = p.get("name", f"{p['type']}_{i}")
        f = pathlib.Path(run_dir) / "probes" / f"{name}.csv"
        if not f.is_file():
            if strict:
                raise Unreadable(f"{f}: no such file (the run was to write every probe of the scene)")
            continue
        d = read_csv(f, columns=("t", col), min_rows=1)
        out[key] = (d["t"], d[col], unit)
    return out


def deviation(run, ref):
    t, v, _ = run
    tr, vr, _ = ref
    keep = tr <= t[-1] + 1e-12
    if not keep.any():
        return float("nan"), float("nan")
    dev = np.interp(tr[keep], t, v) - vr[keep]
    rms = float(np.sqrt(np.mean(dev ** 2)))
    span = float(vr.max() - vr.min())
    return rms, (rms / span if span > 0 else float("nan"))


def experiment_series(run_dir, probe, measured):
    """A probe with an `experiment` object, made dimensionless as the experiment is: returns
    (T, Z) of the run and (te, ze), the measured data (`measured`, from read_experiments). A
    probe file that cannot be read is Unreadable."""
    e = probe["experiment"]
    f = pathlib.Path(run_dir) / "probes" / f"{probe.get('name')}.csv"
    col = series_of(probe, 0)[1]
    d = read_csv(f, columns=("t", col), min_rows=1)
    T = d["t"] * e.get("t_scale", 1.0)
    Z = (d[col] - e.get("value_offset", 0.0)) * e.get("value_scale", 1.0)
    return T, Z, measured[0], measured[1]


SHIFT_STEP = 0.005  # the time-shift grid, in the experiment's (dimensionless) time


def shifted_error(T, Z, te, ze, t_range, max_shift, points_shift=None, report_bound=False):
    """RMS relative error of Z(T) against (te, ze), minimised over one time shift on the grid
    k * SHIFT_STEP with |dT| <= max_shift: returns (error, shift), or (nan, 0) if no shift fits.
    The measured points are those in t_range that the run reaches at a shift of points_shift
    (default max_shift), so that a wider search compares the same points; shifts that would need
    the run beyond its first or last sample are skipped, never extrapolated. "Relative" divides by
    the measured value at each point; points whose |value| is below 1 % of the largest |value| in
    the range are left out (near a zero the ratio measures nothing). With report_bound, also
    returns whether the best shift is the first or last one tried (the search's bound: ±max_shift,
    or where the run ends), so that a better fit may lie beyond it."""
    lo, hi = t_range
    ps = max_shift if points_shift is None else points_shift
    sel = (te >= lo) & (te <= hi) & (te - ps <= T[-1])
    if sel.any():
        sel &= np.abs(ze) >= 0.01 * np.abs(ze[sel]).max()
    best = (float("nan"), 0.0)
    tried = []
    if sel.any():
        n = int(np.floor(max_shift / SHIFT_STEP + 1e-9))  # never beyond max_shift
        for k in range(-n, n + 1):
            shift = SHIFT_STEP * k
            t = te[sel] - shift
            if t.max() > T[-1] + 1e-12 or t.min() < T[0] - 1e-12:
                continue
            tried.append(shift)
            err = float(np.sqrt(np.mean(((np.interp(t, T, Z) - ze[sel]) / ze[sel]) ** 2)))
            if not err >= best[0]:  # also replaces the initial nan
                best = (err, shift)
    if not report_bound:
        return best
    return best[0], best[1], len(tried) > 1 and best[1] in (tried[0], tried[-1])


def experiment_error(run_dir, probe, measured):
    e = probe["experiment"]
    T, Z, te, ze = experiment_series(run_dir, probe, measured)
    return shifted_error(T, Z, te, ze, e.get("t_range", [-1e300, 1e300]), e.get("max_shift", 0.0), report_bound=True)


def wave_figures(run_dir, fluid_probe, summary, scene_json):
    """A scene with a `standing_wave`: the period and amplitude decay of the fluid's centre of
    mass after the wave is given (zero crossings of centre_x about its resting value; slope of
    ln |extremum| against time, parabola-refined extrema), beside linear theory from the run's
    summary.json (Lamb 1932 sec. 348; tests/validation/standing_wave_test.cpp reads it the same
    way). Mode 1 moves the centre of mass most; even modes do not move it (returns None)."""
    wave = summary.get("standing_wave")
    f = pathlib.Path(run_dir) / "probes" / f"{fluid_probe}.csv"
    if not wave or wave["mode"] % 2 == 0 or not f.is_file():
        return None
    d = read_csv(f)
    if "centre_x" not in d or not (d["t"] > wave["at"]).any():  # no column, or the run ends before the wave
        return None
    t, x = d["t"], d["centre_x"]
    at = wave["at"]
    before = (t < at) & (t >= at - 0.2)
    if before.any():
        rest = float(np.mean(x[before]))
    else:
        box = scene_json["fluid_blocks"][0]
        rest = 0.5 * (box["min"][0] + box["max"][0])
    keep = t > at
    t, x = t[keep] - at, x[keep] - rest
    zeros = [t[i - 1] + (t[i] - t[i - 1]) * x[i - 1] / (x[i - 1] - x[i])
             for i in range(1, len(t)) if (x[i - 1] < 0) != (x[i] < 0)]
    ext_t, ext_v, i0 = [], [], 0
    for z in range(len(zeros) + 1):
        t_end = zeros[z] if z < len(zeros) else t[-1] + 1
        idx = [i for i in range(i0, len(t)) if t[i] < t_end]
        if idx:
            best = max(idx, key=lambda i: abs(x[i]))
            i0 = idx[-1] + 1
            if 0 < best < len(t) - 1 and z < len(zeros):  # an interior extremum, its half-cycle closed
                y0, y1, y2 = abs(x[best - 1]), abs(x[best]), abs(x[best + 1])
                den = y0 - 2 * y1 + y2
                off = 0.5 * (y0 - y2) / den if den != 0 else 0.0
                ext_t.append(t[best] + off * (t[best + 1] - t[best]))
                ext_v.append(y1 - 0.25 * (y0 - y2) * off)
    out = {"period_theory_s": wave["period_theory_s"], "decay_theory_per_s": wave["decay_theory_per_s"],
           "period_s": float("nan"), "decay_per_s": float("nan"), "crossings": len(zeros), "extrema": len(ext_t)}
    if len(zeros) >= 3:
        out["period_s"] = 2 * (zeros[-1] - zeros[0]) / (len(zeros) - 1)
    if len(ext_t) >= 3:
        out["decay_per_s"] = -float(np.polyfit(ext_t, np.log(ext_v), 1)[0])
    return out


def pareto_front(points):
    """Indices of the non-dominated points (smaller wall time and smaller error are better)."""
    front = []
    for i, (x, y) in enumerate(points):
        if not (math.isfinite(x) and math.isfinite(y)):
            continue
        dominated = any(x2 <= x and y2 <= y and (x2 < x or y2 < y) for j, (x2, y2) in enumerate(points) if j != i
                        and math.isfinite(x2) and math.isfinite(y2))
        if not dominated:
            front.append(i)
    return sorted(front, key=lambda i: points[i][0])


def fmt(x, digits=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    if x == 0:
        return "0"
    return f"{x:.{digits}g}"


def main():
    ap = argparse.ArgumentParser(prog="sph-study", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--config", action="append", default=[], help="MODE [--set KEY=VALUE ...] [--name LABEL]")
    ap.add_argument("--no-default-modes", action="store_true", help="run only the --config configurations")
    ap.add_argument("--set", action="append", default=[], help="override for every run (and the reference)")
    ap.add_argument("--end", type=float, help="simulated seconds (default: the scene's end_time)")
    ap.add_argument("--scale", type=float, help="particle-count multiplier (default: the scene's)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reference", help="an earlier run's output folder to use as the reference")
    ap.add_argument("--reference-dt", type=float, help="step of the reference run (default: half the smallest "
                                                      "step of the global run)")
    ap.add_argument("--out", help="output folder (default out/study/<scene name>)")
    default_run = HERE / "sph-run"
    if not default_run.exists():
        default_run = HERE.parent / "build" / "tools" / "sph-run"
    ap.add_argument("--sph-run", default=str(default_run))
    args = ap.parse_args()
    if not pathlib.Path(args.sph_run).exists():
        fail(f"{args.sph_run}: not found (build first: cmake --build build)")

    if args.reference_dt is not None and not args.reference_dt > 0:
        fail(f"--reference-dt {args.reference_dt}: expected a step > 0 s")
    if args.threads < 1:
        fail(f"--threads {args.threads}: expected at least 1")
    errors_as_exit_2()  # an output that cannot be written: one line, exit 2; Ctrl-C, SIGTERM: die by it
    study = Study(args)
    if args.reference:  # checked before any run, not after all of them
        why = study.load_reference(pathlib.Path(args.reference), f"--reference {args.reference}", strict=False)
        if why:
            fail(why)
        study.ref_note = None
    known = {tuple(m) for m in study.list_modes()}  # every "method mode" pair the scene loads with
    for spec in args.config:
        c = parse_config(spec)
        method = c["method"] or study.scene_method()
        if (method, c["mode"]) not in known:
            fail(f"--config {spec!r}: no mode {method}/{c['mode']} for this scene (it loads with: "
                 + ", ".join(f"{m}/{o}" for m, o in sorted(known)) + ")")
    study.configs = study.configurations()  # "no configurations": exit 2 before anything is written
    study.measured = read_experiments(study.scene, study.probes)  # before any run: a bad file stops the study now
    # Every argument checked: now the output folder, and the runs' copy of the scene in it.
    try:
        study.out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        fail(f"--out {study.out}: cannot create the output folder ({e.strerror or e})")
    study.write_scene()
    rows, text = study.run()
    print()
    print(text)
    configs, results = study.configs, study.results
    wrote = [study.out / "study.md", study.out / "study.csv"]

    # ---- Pareto plot (none without a reference: no error axis) ----
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if study.ref_note is None:
        ok = [r for r in rows if r["status"] == "ok"]
        pts = [(r["wall_s"], r["deviation (mean rel.)"]) for r in ok]
        front = pareto_front(pts)
        fig, ax = plt.subplots(figsize=(7, 4.5), dpi=110)
        ax.scatter([p[0] for p in pts], [p[1] for p in pts], color="0.5", zorder=2, label="configuration")
        if front:
            ax.plot([pts[i][0] for i in front], [pts[i][1] for i in front], "-o", color="tab:red", zorder=3,
                    label="non-dominated (Pareto front)")
        for r, (x, y) in zip(ok, pts):
            if math.isfinite(y):
                ax.annotate(r["configuration"], (x, y), textcoords="offset points", xytext=(5, 4), fontsize=8)
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("deviation from the reference (mean RMS / range)")
        ax.set_title(f"{study.scene_json.get('name')}: speed against accuracy ({args.threads} threads, "
                     f"{study.started.strftime('%Y-%m-%d')})", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(study.out / "pareto.png")
        wrote.append(study.out / "pareto.png")
    # ---- dt over time (He Fig. 2: dt_sim and the active fraction; Ihmsen Fig. 4: dt), every run ----
    plot = HERE / "plot_dt.py"
    if not plot.is_file():
        plot = HERE.parent.parent / "tools" / "plot_dt.py"  # build/tools/sph-study -> tools/plot_dt.py
    runs = [(r["_dir"], c["label"]) for r, c in zip(results, configs) if r]
    if plot.is_file() and runs:
        cmd = [sys.executable, str(plot)] + [d for d, _ in runs] + sum((["--label", l] for _, l in runs), []) + \
              ["--out", str(study.out / "dt.png"), "--title", f"{study.scene_json.get('name')}: Δt_sim and active fraction"]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            print(f"sph-study: warning: plot_dt.py failed: {proc.stderr.strip()}", file=sys.stderr)
        else:
            wrote.append(study.out / "dt.png")
    elif runs:
        print(f"sph-study: warning: no dt.png: plot_dt.py is not beside {HERE / 'sph-study'}", file=sys.stderr)
    print("wrote " + ", ".join(str(f) for f in wrote))
    # What the tables could not say: exit 2, after they are written, with one line. A failed run
    # (and a constant one skipped for it) is a result of the study; an unreadable or interrupted one is not.
    reference = [] if study.ref_note is None else \
        [f"the accuracy columns are unavailable: {study.ref_note.split(': ', 1)[1]}"]
    exit_if_unusable([f"{c['label']}: {p}" for c, p in zip(configs, study.problems)
                      if p and p.startswith(("unreadable", "interrupted"))],
                     f"{study.out / 'study.csv'} and study.md", before=reference)


if __name__ == "__main__":
    main()
