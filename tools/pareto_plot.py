#!/usr/bin/env python3
"""Pareto plot of wall time against the maximum average density error from a CSV with the
columns engine, configuration, wall_s, max_avg_density_error_percent (docs/results/dfsph_pareto.csv).

    tools/pareto_plot.py docs/results/dfsph_pareto.csv docs/results/figures/dfsph_pareto.png
"""
import csv
import sys

from sph_python import errors_as_exit_2, need, usage_unless  # noqa: E402 (tools/ is the script's folder)

errors_as_exit_2()
usage_unless(2, __doc__)

need("matplotlib")
import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

rows = list(csv.DictReader(open(sys.argv[1])))
fig, ax = plt.subplots(figsize=(7, 4.5))
for engine, marker in (("ours", "o"), ("SPlisHSPlasH (scaled)", "s")):
    pts = [r for r in rows if r["engine"] == engine]
    ax.scatter([float(r["max_avg_density_error_percent"]) for r in pts], [float(r["wall_s"]) for r in pts],
               marker=marker, label=engine, facecolors="none" if engine != "ours" else None, edgecolors="k")
    for r in pts:
        ax.annotate(r["configuration"], (float(r["max_avg_density_error_percent"]), float(r["wall_s"])),
                    fontsize=7, xytext=(4, 2), textcoords="offset points")
ax.set_xscale("log")
ax.set_xlabel("max average density error (%)")
ax.set_ylabel("wall time (s), peer_dam_break 1 s, 2 threads")
ax.legend(fontsize=8)
ax.grid(True, which="both", alpha=0.3)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
print(f"pareto_plot.py: wrote {sys.argv[2]}")
