#!/usr/bin/env python3
"""How much per-particle stepping could at most gain over a WCSPH run with the acoustic condition.

Reads an `sph-run` output folder (summary.json, stats.csv) and prints

* E0, the fewest evaluations per particle any stepping that keeps the acoustic condition can
  make over the run's simulated time T: a particle i may step at most
  dt_i = min(dt_max, Morris et al. 1997 eq. 12, lambda_c h / (c_s + |v_i|)) (the per-particle
  bound of systems/forces/forces_system.cpp; StepBound in systems/timestep/global_dt_system.hpp),
  so over a step k of length dt_k the particles make at least mean_i dt_k / dt_i evaluations
  each, which is at least dt_k max(1 / dt_max, 1 / Morris, (c_s + vbar_k) / (lambda_c h)) with
  vbar_k the mean speed (stats.csv's v_mean; the maximum of affine functions is convex, so the
  mean speed gives a lower bound). E0 is the sum over the run's steps. vbar_k is used on steps
  that evaluated every row (where v_mean is the whole fluid's), 0 on the others and in a
  stats.csv without v_mean (older runs): then E0 = T / dt_c with dt_c the bound at v = 0.
* the evaluations per particle the run made (the sum over steps of the share evaluated);
* their ratio. For a `global` or `constant` run it bounds the ratio of evaluations by which any
  per-particle stepping (`binned`, `individual`) at the same lambda_c can undercut the run, and
  so its speed-up as long as a step over a subset costs at least what `global` pays per
  evaluation (measured: it costs more). For a `binned` run it says how far its evaluations lie
  above that ideal (power-of-two bins, the limiter, the fast particles).

docs/methods.md ("Binned stepping") and docs/results/he_table1.md use it. Bad input (no
folder, not an sph-run summary, not WCSPH, the acoustic condition off, a stats.csv that holds
fewer steps than the run kept, e.g. after a resume into a new folder) exits 2 naming the file.

Usage: tools/stepping_bound.py RUN_DIR [RUN_DIR ...]
"""
import csv
import json
import sys


class BadInput(Exception):
    """An input the tool cannot use; the message names the file and what was expected."""


def bound(run_dir):
    """The figures of one run folder (a dict); BadInput when it cannot be used."""
    where = f"{run_dir}/summary.json"
    try:
        with open(where) as f:
            s = json.load(f)
        if s.get("method") != "wcsph":
            raise BadInput(f"{where}: method {s.get('method')!r}: the bound is for WCSPH runs")
        sp = s["stepping_params"]
        ph = s["physics"]
        h, c, nu = float(ph["support_radius"]), float(ph["speed_of_sound"]), float(ph["kinematic_viscosity"])
        dt_max, lambda_c, acoustic = float(sp["dt_max"]), float(sp["lambda_c"]), bool(sp["acoustic"])
        stepping, kept = str(s["stepping"]), int(s["kept_steps"])
    except BadInput:
        raise
    except OSError as e:
        raise BadInput(f"{where}: {e.strerror or e}") from None
    except (ValueError, KeyError, TypeError, AttributeError) as e:
        raise BadInput(f"{where}: {e!r} (expected sph-run's summary with physics and stepping_params, "
                       "which sph-run writes since 2026-12-06)") from None
    if not acoustic:
        raise BadInput(f"{where}: the acoustic condition is off, so no step has a sound-crossing bound")
    if not (h > 0 and c > 0 and lambda_c > 0 and dt_max > 0 and nu >= 0):
        raise BadInput(f"{where}: support_radius {h}, speed_of_sound {c}, lambda_c {lambda_c}, dt_max {dt_max} "
                       f"and kinematic_viscosity {nu}: expected positive values (nu >= 0)")
    # The per-particle cap that does not depend on the speed: dt_max and Morris et al. 1997
    # eq. 12, as StepBound.
    cap = dt_max if nu == 0 else min(dt_max, 0.125 * (0.5 * h) ** 2 / nu)
    dt_c = min(cap, lambda_c * h / c)
    where = f"{run_dir}/stats.csv"
    t = made = ideal = t_speed = 0.0
    steps = 0
    try:
        with open(where) as f:
            for row in csv.DictReader(f):  # WCSPH: every row is a kept step (no rollback)
                dt, share = float(row["dt"]), float(row["active_fraction"])
                v = 0.0
                if share == 1.0 and row.get("v_mean") not in (None, ""):
                    v = float(row["v_mean"])
                    t_speed += dt
                ideal += dt * max(1 / cap, (c + v) / (lambda_c * h))
                t += dt
                made += share
                steps += 1
    except OSError as e:
        raise BadInput(f"{where}: {e.strerror or e}") from None
    except (KeyError, ValueError, TypeError) as e:
        raise BadInput(f"{where}: {e!r} (expected sph-run's stats.csv with dt and active_fraction)") from None
    if steps == 0 or not t > 0:
        raise BadInput(f"{where}: no steps")
    if steps != kept:
        raise BadInput(f"{where}: holds {steps} steps of the run's {kept} (a run resumed into another folder? "
                       "use the folder that holds every step)")
    return {"run": run_dir, "stepping": stepping, "lambda_c": lambda_c, "steps": steps, "simulated_s": t,
            "dt_c": dt_c, "evaluations_per_particle": made, "bound_evaluations_per_particle": ideal,
            "bound_at_rest": t / dt_c, "speed_share": t_speed / t, "ratio": made / ideal}


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
        what = ("bound on per-particle stepping's evaluation ratio" if b["stepping"] in ("global", "constant")
                else "evaluations above that ideal")
        print(f"{b['run']}: {b['stepping']}, lambda_c {b['lambda_c']:g}, {b['steps']} steps over {b['simulated_s']:g} s; "
              f"evaluations per particle {b['evaluations_per_particle']:.0f}, at the sound-crossing bound "
              f"{b['bound_evaluations_per_particle']:.0f} (at rest, {1e3 * b['dt_c']:.4g} ms: {b['bound_at_rest']:.0f}; "
              f"mean speeds over {100 * b['speed_share']:.0f} % of the time); {what}: {b['ratio']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
