#!/usr/bin/env bash
# Installs what is missing, builds Release and runs the default scene (scenes/dam_break.json).
# Outputs: out/dam_break/{stats.csv,summary.json,frames/*.vtu}. Extra arguments go to sph-run
# (not a scene or --out: those are passed here).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install_deps.sh
# Ninja for a new build tree (an existing one keeps its generator): unlike Makefiles it compiles
# a target's sources while the libraries it links are still being built (docs/results/ci.md).
export CMAKE_GENERATOR="${CMAKE_GENERATOR:-Ninja}"
# A new build tree skips the tests and benchmarks (only sph-run is built here); an existing one keeps
# its own options, so that running this does not switch off a developer's test targets.
if [ -f build/CMakeCache.txt ]; then
  cmake -S . -B build >/dev/null
else
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSPH_BUILD_TESTS=OFF -DSPH_BUILD_BENCH=OFF >/dev/null
fi
cmake --build build --target sph-run -j"$(nproc)"
./build/tools/sph-run scenes/dam_break.json --out out/dam_break "$@"
echo "summary: out/dam_break/summary.json"
cat out/dam_break/summary.json
