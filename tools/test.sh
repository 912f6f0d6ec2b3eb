#!/usr/bin/env bash
# Installs what is missing, builds everything (Release) and runs the whole test suite; then
# (CI, and by default) the sanitizer builds and the loader fuzzer:
#   1. Release build (build-test/), every test (ctest).
#   2. AddressSanitizer + UndefinedBehaviorSanitizer build: the unit tests and the malformed
#      corpus through sph-run (the long physics runs and the other end-to-end scripts are left
#      to stage 1: they cover no code the unit tests do not, at 3-10x the time).
#   3. ThreadSanitizer build, linked against a TSan-instrumented oneTBB built from Debian's source
#      (tools/install_tsan_tbb.sh): the graph and system tests (flow graph, per-system parallel
#      loops, the NaN trace inside the graph's nodes, PCISPH and the emitter, checkpoints, the
#      binned limiter's concurrent pushes).
#   4. libFuzzer on the scene loader for SPH_FUZZ_SECONDS (default 60).
# SPH_TEST_SANITIZERS=0 runs stage 1 only (a quick local check).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install_deps.sh --test
# Ninja for every new build tree (an existing one keeps its generator): with Makefiles a target's
# sources wait until every library it links is built, so the two cores sat half idle behind
# engine/run/surface.cpp (OpenVDB, 100 s under ASan): stage 2's build 12 min 23 s with Makefiles,
# 8 min 25 s with Ninja for more targets (docs/results/ci.md).
export CMAKE_GENERATOR="${CMAKE_GENERATOR:-Ninja}"
jobs=$(nproc)
stage() { echo; echo "=== $1 ($(date -u +%H:%M:%S))"; }
t0=$(date +%s)

stage "1/4 Release build and the whole suite"
# In build-test/, the two libraries as unity builds (CMAKE_UNITY_BUILD, batches of 8 sources): the
# stage 10.7 min instead of 14 on two cores, the same runs to the bit (docs/results/ci.md). Not in
# build/: a unity build runs 5 % slower (GCC inlines less in a large unit), and build/ is where
# tools/run.sh builds and the benchmarks are measured, one translation unit per source.
cmake -S . -B build-test -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON -DSPH_BUILD_TESTS=ON -DSPH_BUILD_BENCH=ON >/dev/null
cmake --build build-test -j"$jobs"
ctest --test-dir build-test --output-on-failure -j"$jobs" --timeout 1200
# Every test's output, passing ones too (the figures they print beside their bounds), kept as
# build-test/stage1-tests.log: the ctest calls below (--show-only) rewrite LastTest.log.
cp build-test/Testing/Temporary/LastTest.log build-test/stage1-tests.log
[ "${SPH_TEST_SANITIZERS:-1}" = "0" ] && exit 0

# Sanitizer builds: -O1 (fast enough to run, much faster to compile than -O2), -g1 (line tables:
# file and line in every report; 15-30 % less compile time than -g), asserts on, every report
# fatal; the two libraries as unity builds (CMAKE_UNITY_BUILD: batches of 8 sources, a third of
# the compile time; the Highway dispatch sources stay apart), as in stage 1.
# Measured in docs/results/ci.md.
sanitizer_build=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DCMAKE_UNITY_BUILD=ON
                 -DSPH_BUILD_TESTS=ON -DSPH_BUILD_BENCH=OFF)
# LeakSanitizer is off: every test that runs a flow graph reports 64 bytes in 2 objects
# allocated inside libstdc++ (unsymbolised; oneTBB's worker threads outlive main(), the likely
# owners), which no suppression can single out without hiding our own std allocations.
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$PWD/tests/ubsan.supp"
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp"
# The long physics runs and end-to-end scripts (stage 1 runs them); the validation and PCISPH
# smoothness runs are tens of seconds in Release and several minutes under ASan.
long='RunRobustnessCli|SteppingBound|ParaViewReadsRun|BlenderImportsRun|Hydrostatic|DamBreak|Stirring\.Pushed|MillionSteps|EqualStepsReproduceGlobal|InstallAndConsume|SphRunCli|ToolsPlots|CheckpointCli|ModeAgreement|MartinMoyce|KoshizukaOka|PcisphSmoothness|SphStudy|ResolutionStudy|StandingWave|WallEnergy'

stage "2/4 AddressSanitizer + UndefinedBehaviorSanitizer: unit tests"
# The test sources at -O0 (SPH_TEST_FLAGS; the engine stays at -O1): 13 % less build time for
# this stage, the same test time (docs/results/ci.md).
cmake -S . -B build-asan "${sanitizer_build[@]}" -DSPH_SANITIZE="address;undefined" -DSPH_TEST_FLAGS=-O0 >/dev/null
# sph-run (the corpus) and every test executable holding a test outside the long pattern, read
# from stage 1's test list (an executable's tests carry its name as label); the others are not
# built, and their placeholder tests, <name>_NOT_BUILT, are excluded with the long ones.
asan_targets=(sph-run $(ctest --test-dir build-test --show-only=json-v1 | python3 -c '
import json, re, sys
long = re.compile(sys.argv[1])
print(*sorted({p["value"][0] for t in json.load(sys.stdin)["tests"] if not long.search(t["name"])
               for p in t.get("properties", []) if p["name"] == "LABELS"}))' "$long"))
cmake --build build-asan -j"$jobs" --target "${asan_targets[@]}"
ctest --test-dir build-asan --output-on-failure -j"$jobs" --timeout 1200 -E "$long|_NOT_BUILT\$"

stage "3/4 ThreadSanitizer: graph and system tests, against a TSan-instrumented oneTBB"
# Debian's libtbb is not instrumented, so TSan would not see how oneTBB hands tasks between
# threads; tools/install_tsan_tbb.sh builds Debian's own oneTBB 2021.8.0 source with
# -fsanitize=thread (cached in build-tbb-tsan/, about 35 s).
tbb_dir=$(bash tools/install_tsan_tbb.sh)
tsan_targets=(system_graph_test individual_systems_test forces_system_test boundary_motion_system_test
              grid_test checkpoint_test extremes_test emitter_system_test pcisph_test nonpressure_forces_system_test
              gradient_correction_system_test vectorised_paths_test dfsph_test wall_pressure_system_test
              binned_step_system_test drift_system_test)
# Without OpenVDB here: Debian's libopenvdb links Debian's (uninstrumented) libtbb, and no test
# of this stage writes a surface.
cmake -S . -B build-tsan "${sanitizer_build[@]}" -DSPH_SANITIZE=thread -DTBB_DIR="$tbb_dir" -DSPH_WITH_OPENVDB=OFF >/dev/null
cmake --build build-tsan -j"$jobs" --target "${tsan_targets[@]}"
# A stage that silently ran against the uninstrumented library would prove nothing.
# (ldd's output is captured first: `ldd | grep -q` under pipefail fails whenever grep exits before
# ldd has written everything and ldd dies of SIGPIPE; that failed a CI run.)
tsan_libs=$(ldd build-tsan/tests/system_graph_test)
[[ "$tsan_libs" == *"build-tbb-tsan/install/lib/libtbb"* ]] ||
  { echo "build-tsan does not load the instrumented oneTBB:"; echo "$tsan_libs"; exit 1; }
# The canary: a seeded race between two flow-graph nodes must be reported (TSan exits 66).
tbb_prefix=${tbb_dir%/lib/cmake/TBB}
g++ -std=c++20 -O1 -g -fsanitize=thread tests/tsan/race_canary.cpp -I"$tbb_prefix/include" -L"$tbb_prefix/lib" \
  -Wl,-rpath,"$tbb_prefix/lib" -ltbb -o build-tsan/race_canary
if TSAN_OPTIONS=halt_on_error=1 ./build-tsan/race_canary >build-tsan/race_canary.log 2>&1 ||
   ! grep -q "WARNING: ThreadSanitizer: data race" build-tsan/race_canary.log; then
  echo "ThreadSanitizer did not report the seeded race of tests/tsan/race_canary.cpp:"; cat build-tsan/race_canary.log; exit 1
fi
echo "race canary: ThreadSanitizer reports the seeded race between two flow-graph nodes"
tsan_tests=$(printf '%s|' "${tsan_targets[@]}")
ctest --test-dir build-tsan --output-on-failure -j"$jobs" --timeout 1200 -E "$long" -L "^(${tsan_tests%|})$"

stage "4/4 libFuzzer: scene loader, ${SPH_FUZZ_SECONDS:-60} s"
bash tools/fuzz.sh "${SPH_FUZZ_SECONDS:-60}"

echo; echo "all stages passed in $(( ($(date +%s) - t0) / 60 )) min $(( ($(date +%s) - t0) % 60 )) s"
