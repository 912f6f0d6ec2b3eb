#!/usr/bin/env bash
# Fuzzes the scene loader, then the checkpoint reader, with libFuzzer (Debian's clang) for a
# bounded time (SECONDS for the loader, half of it for the checkpoint reader):
#   bash tools/fuzz.sh [SECONDS] [--merge]
# Seeds: tests/data/fuzz_corpus (kept in the repository), scenes/ and the malformed corpus;
# tests/data/checkpoint_corpus for checkpoints.
# Any crash, sanitizer report, uncaught non-InputError exception, or an input taking more
# than 10 s fails (exit non-zero; the reproducer is written to build-fuzz/). --merge folds the
# new inputs it found, minimised, back into tests/data/fuzz_corpus.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
out=build-fuzz
mkdir -p "$out/corpus"
cxx=$(command -v clang++ || command -v clang++-14)
flags=(-std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -I. -I/usr/include/eigen3)
# The scene loader and what it links: the schema, its three stages, motions, probes, errors.
sources=(engine/data/scene.cpp engine/data/scene_text.cpp engine/data/scene_overrides.cpp engine/data/scene_reader.cpp
         engine/data/motion.cpp engine/data/probe_desc.cpp engine/core/errors.cpp)
# The checkpoint reader: the container and the meta keys (engine/run/checkpoint_file.cpp).
ck_sources=(engine/run/checkpoint_file.cpp engine/core/errors.cpp)
# Both fuzzers are rebuilt when either is missing or older than a source or header it reads;
# their sources are compiled one per core (the serial compile was half of this stage's time).
if [ ! -x "$out/scene_fuzzer" ] || [ ! -x "$out/checkpoint_fuzzer" ] ||
   [ -n "$(find "${sources[@]}" "${ck_sources[@]}" engine/data/*.hpp engine/core/*.hpp engine/run/checkpoint.hpp \
             tests/fuzz/*.cpp -newer "$out/scene_fuzzer" -o -newer "$out/checkpoint_fuzzer" 2>/dev/null)" ]; then
  mkdir -p "$out/obj"
  obj() { local o=${1//\//_}; echo "$out/obj/${o%.cpp}.o"; }
  printf '%s\n' tests/fuzz/scene_fuzzer.cpp tests/fuzz/checkpoint_fuzzer.cpp "${sources[@]}" engine/run/checkpoint_file.cpp |
    xargs -P "$(nproc)" -I{} bash -c 'o=${1//\//_}; exec "${@:3}" -c "$1" -o "$2/obj/${o%.cpp}.o"' _ {} "$out" "$cxx" "${flags[@]}"
  scene_objs=() ck_objs=()
  for s in tests/fuzz/scene_fuzzer.cpp "${sources[@]}"; do scene_objs+=("$(obj "$s")"); done
  for s in tests/fuzz/checkpoint_fuzzer.cpp "${ck_sources[@]}"; do ck_objs+=("$(obj "$s")"); done
  "$cxx" "${flags[@]}" "${scene_objs[@]}" -o "$out/scene_fuzzer"
  "$cxx" "${flags[@]}" "${ck_objs[@]}" -o "$out/checkpoint_fuzzer"
fi
# Work on a copy: the repository's corpus changes only with --merge.
rm -rf "$out/corpus"/*
cp tests/data/fuzz_corpus/* "$out/corpus/" 2>/dev/null || true
cd "$out"
./scene_fuzzer -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=4096 \
  -dict=../tests/fuzz/scene.dict -print_final_stats=1 corpus ../scenes ../tests/data/malformed 2>&1 | tail -15
cd ..
rm -rf "$out/ck_corpus" && mkdir -p "$out/ck_corpus" && cp tests/data/checkpoint_corpus/* "$out/ck_corpus/"
(cd "$out" && ./checkpoint_fuzzer -max_total_time="$(( (seconds + 1) / 2 ))" -timeout=10 -rss_limit_mb=2048 \
   -max_len=4096 -print_final_stats=1 ck_corpus 2>&1 | tail -8)
if [ "${2:-}" = "--merge" ]; then
  "$out/checkpoint_fuzzer" -merge=1 tests/data/checkpoint_corpus "$out/ck_corpus" 2>&1 | tail -2
  mkdir -p tests/data/fuzz_corpus
  "$out/scene_fuzzer" -merge=1 tests/data/fuzz_corpus "$out/corpus" 2>&1 | tail -2
fi
