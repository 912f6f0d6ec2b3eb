#!/usr/bin/env python3
"""Turns Google Benchmark JSON (--benchmark_out) into the Markdown tables of
docs/results/benchmarks.md: medians of repetitions where present, with the machine context and
date the run recorded; then the thread-scaling pairs and, for BM_Individual_* and BM_Binned_*,
one row per system with a column per active share.

usage: tools/bench_table.py out/bench.json
"""
import json
import re
import sys
from sph_python import errors_as_exit_2, usage_unless  # noqa: E402 (tools/ is the script's folder)

errors_as_exit_2()

usage_unless(1, __doc__)
try:
    with open(sys.argv[1]) as f:
        data = json.load(f)
except (OSError, json.JSONDecodeError) as e:
    print(f"bench_table: {sys.argv[1]}: {e}", file=sys.stderr)
    sys.exit(2)
if not isinstance(data, dict) or "benchmarks" not in data or "context" not in data:
    print(f"bench_table: {sys.argv[1]}: not Google Benchmark JSON (no \"context\" and \"benchmarks\")", file=sys.stderr)
    sys.exit(2)
ctx = data["context"]
# With --benchmark_repetitions a run has iteration rows and aggregate rows: keep the median
# aggregate only; a run without repetitions has just its iteration row. Sorted by name, since
# --benchmark_enable_random_interleaving shuffles the order.
aggregated = {b["run_name"] for b in data["benchmarks"] if b.get("run_type") == "aggregate"}
rows = [b for b in data["benchmarks"]
        if (b.get("aggregate_name") == "median") or (b.get("run_type") != "aggregate" and b["run_name"] not in aggregated)]
rows.sort(key=lambda b: b["run_name"])
reps = rows[0].get("repetitions", 1) if rows else 1
print(f"`sph-bench` on {ctx.get('num_cpus')} × {ctx.get('mhz_per_cpu')} MHz, {ctx.get('date')}; engine built Release "
      f"(Debian's libbenchmark reports itself as {ctx.get('library_build_type')}); "
      + (f"medians of {reps} repetitions.\n" if reps > 1 else "one run each.\n"))
print("| benchmark | particles | time per iteration | items/s | neighbours/particle | bytes/particle |")
print("|---|---|---|---|---|---|")
for b in rows:
    name = re.sub(r"/min_time:[0-9.]+", "", b["run_name"]).replace("/real_time", "")
    n = b.get("particles", b.get("fluid_particles", 0))
    unit = b.get("time_unit", "ns")
    bpp = b.get("bytes_per_particle")
    ips = b.get("items_per_second")  # absent where a benchmark counts no items (BM_Binned_body)
    print(f"| `{name}` | {n:,.0f} | {b['real_time']:.3g} {unit} | {f'{ips / 1e6:.2f} M' if ips else ''} | "
          f"{b.get('neighbours_per_particle', 0):.1f} | {'%.0f' % bpp if bpp else ''} |")

# Thread scaling, from the same run: the ratio of the 1-thread to the 2-thread median.
by_name = {re.sub(r"/min_time:[0-9.]+", "", b["run_name"]).replace("/real_time", ""): b for b in rows}
pairs = [(n, n.replace("threads:1", "threads:2")) for n in by_name if "threads:1" in n]
pairs = [(a, b) for a, b in pairs if b in by_name]
if pairs:
    print("\n| benchmark | 1 thread | 2 threads | speed-up |")
    print("|---|---|---|---|")
    for a, b in pairs:
        t1, t2 = by_name[a]["real_time"], by_name[b]["real_time"]
        unit = by_name[a].get("time_unit", "ns")
        print(f"| `{a.replace('/threads:1', '')}` | {t1:.3g} {unit} | {t2:.3g} {unit} | {t1 / t2:.2f}× |")

# Individual stepping (He et al. Alg. 2) and binned stepping by active share, from the same run: one row per system
# and particle count, one column per share (BM_Individual_<system>/<N>/<active per mille>), and
# the cost at 10 % relative to 100 % (1.0 = does not scale with the active set, 0.1 = in proportion).
for family, label in (("Individual", "individual"), ("Binned", "binned")):
    shares = {}
    for name, b in by_name.items():
        m = re.fullmatch(rf"BM_{family}_(\w+)/(\d+)/(\d+)", name)
        # The last argument is the active share in per mille (1000, 500, 100, 10); other
        # families' last argument means something else (BM_Binned_body/N/{0,1}: a moving body).
        if m and int(m.group(3)) in (1000, 500, 100, 10):
            shares.setdefault((m.group(1), int(m.group(2))), {})[int(m.group(3))] = b
    if not shares:
        continue
    cols = sorted({a for row in shares.values() for a in row}, reverse=True)
    print(f"\n| {label} system | particles | " + " | ".join(f"{a / 10:g} % active" for a in cols) +
          " | 10 % / 100 % |")
    print("|---|---|" + "---|" * len(cols) + "---|")
    for (system, n), row in sorted(shares.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        unit = next(iter(row.values())).get("time_unit", "ns")
        cells = [f"{row[a]['real_time']:.3g} {unit}" if a in row else "" for a in cols]
        ratio = f"{row[100]['real_time'] / row[1000]['real_time']:.2f}" if 100 in row and 1000 in row else ""
        print(f"| `{system}` | {n:,} | " + " | ".join(cells) + f" | {ratio} |")
