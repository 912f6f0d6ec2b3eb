#!/usr/bin/env python3
"""How much per-particle stepping could at most gain over a WCSPH run with the acoustic condition.

Reads an `sph-run` output folder (summary.json, stats.csv) and prints

* E, the evaluations per particle a particle would need if it stepped, all run long, at exactly
  the sound-crossing bound the run used: E = sum_k dt_k / dt_c,k with
  dt_c,k = min(dt_max, Morris et al. 1997 eq. 12, lambda_c h / (c_s + v_max,k)), the bound the
  step-size system put on step k (v_max,k is the row's: the statistics the step was sized from);
* the evaluations per particle the run made (the sum over steps of the share evaluated);
* their ratio. For a `global` or `constant` run it bounds the speed-up of any per-particle
  stepping (`binned`, `individual`) at the same lambda_c over this run: even with no bookkeeping,
  no particle may step past its sound-crossing bound, so every particle is evaluated at least E
  times. For a `binned` run it says how far its evaluations lie above that ideal (power-of-two
  bins, the limiter, the fast particles); its v_max is over the rows evaluated in each step.

docs/methods.md ("Binned stepping") and docs/results/he_table1.md use it.

Usage: tools/stepping_bound.py RUN_DIR [RUN_DIR ...]
"""
import csv
import json
import sys


class BadInput(Exception):
    """An input the tool cannot use; the message names the file and what was expected."""


def bound(run_dir):
    """The figures of one run folder (a dict); BadInput when it cannot be used."""
    try:
        with open(f"{run_dir}/summary.json") as f:
            s = json.load(f)
    except (OSError, ValueError) as e:
        raise BadInput(f"{run_dir}/summary.json: {e}") from None
    if s.get("method") != "wcsph":
        raise BadInput(f"{run_dir}/summary.json: method {s.get('method')!r}: the bound is for WCSPH runs")
    sp = s.get("stepping_params")
    if sp is None:
        raise BadInput(f"{run_dir}/summary.json: no 'stepping_params' (written by sph-run since 2026-12-06)")
    try:
        ph = s["physics"]
        h, c, nu = ph["support_radius"], ph["speed_of_sound"], ph["kinematic_viscosity"]
        cap, lch, acoustic = sp["dt_max"], sp["lambda_c"] * h, sp["acoustic"]
    except (KeyError, TypeError) as e:
        raise BadInput(f"{run_dir}/summary.json: no {e} (expected sph-run's summary)") from None
    if not acoustic:
        raise BadInput(f"{run_dir}/summary.json: the acoustic condition is off, so no step has a sound-crossing bound")
    if nu > 0:
        cap = min(cap, 0.125 * (0.5 * h) ** 2 / nu)  # Morris et al. 1997 eq. 12, as the step-size systems
    ideal = made = 0.0
    steps = 0
    try:
        with open(f"{run_dir}/stats.csv") as f:
            for row in csv.DictReader(f):
                if row.get("rolled_back", "0") not in ("0", ""):
                    continue
                ideal += float(row["dt"]) / min(cap, lch / (c + float(row["v_max"])))
                made += float(row["active_fraction"])
                steps += 1
    except (OSError, KeyError, ValueError, TypeError) as e:
        raise BadInput(f"{run_dir}/stats.csv: {e!r} (expected sph-run's stats.csv with dt, v_max, active_fraction)") from None
    if steps == 0 or ideal <= 0:
        raise BadInput(f"{run_dir}/stats.csv: no steps")
    return {"run": run_dir, "stepping": s["stepping"], "lambda_c": sp["lambda_c"], "steps": steps,
            "evaluations_per_particle": made, "acoustic_evaluations_per_particle": ideal, "ratio": made / ideal}


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if len(argv) >= 2 else 2
    for d in argv[1:]:
        try:
            b = bound(d)
        except BadInput as e:
            print(f"stepping_bound.py: {e}", file=sys.stderr)
            return 2
        what = ("speed-up bound for per-particle stepping" if b["stepping"] in ("global", "constant")
                else "evaluations above the acoustic ideal")
        print(f"{b['run']}: {b['stepping']}, lambda_c {b['lambda_c']:g}, {b['steps']} steps; evaluations per particle "
              f"{b['evaluations_per_particle']:.0f}, at the sound-crossing bound {b['acoustic_evaluations_per_particle']:.0f}; "
              f"{what}: {b['ratio']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
