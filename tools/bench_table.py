#!/usr/bin/env python3
"""Turns Google Benchmark JSON (--benchmark_out) into the README's Markdown table: medians of
repetitions where present, with the machine context and date the run recorded.

usage: tools/bench_table.py out/bench.json
"""
import json
import re
import sys

data = json.load(open(sys.argv[1]))
ctx = data["context"]
rows = [b for b in data["benchmarks"] if b.get("aggregate_name", "median") == "median"]
print(f"`sph-bench` on {ctx.get('num_cpus')} × {ctx.get('mhz_per_cpu')} MHz, {ctx.get('date')}; engine built Release "
      f"(Debian's libbenchmark reports itself as {ctx.get('library_build_type')}); medians of {rows[0].get('repetitions', 1) if rows else 0} repetitions.\n")
print("| benchmark | particles | time per iteration | items/s | neighbours/particle | bytes/particle |")
print("|---|---|---|---|---|---|")
for b in rows:
    name = re.sub(r"/min_time:[0-9.]+", "", b["run_name"]).replace("/real_time", "")
    n = b.get("particles", b.get("fluid_particles", 0))
    unit = b.get("time_unit", "ns")
    bpp = b.get("bytes_per_particle")
    print(f"| `{name}` | {n:,.0f} | {b['real_time']:.3g} {unit} | {b['items_per_second'] / 1e6:.2f} M | "
          f"{b.get('neighbours_per_particle', 0):.1f} | {'%.0f' % bpp if bpp else ''} |")
