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
# The scene loader and what it links: the schema, its three stages, motions, probes, errors.
sources=(engine/data/scene.cpp engine/data/scene_text.cpp engine/data/scene_overrides.cpp engine/data/scene_reader.cpp
         engine/data/motion.cpp engine/data/probe_desc.cpp engine/core/errors.cpp)
if [ ! -x "$out/scene_fuzzer" ] ||
   [ -n "$(find "${sources[@]}" engine/data/*.hpp engine/core/*.hpp tests/fuzz/scene_fuzzer.cpp -newer "$out/scene_fuzzer")" ]; then
  "$cxx" -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
    -I. -I/usr/include/eigen3 tests/fuzz/scene_fuzzer.cpp "${sources[@]}" \
    -o "$out/scene_fuzzer"
fi
# Work on a copy: the repository's corpus changes only with --merge.
rm -rf "$out/corpus"/*
cp tests/data/fuzz_corpus/* "$out/corpus/" 2>/dev/null || true
cd "$out"
./scene_fuzzer -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=4096 \
  -dict=../tests/fuzz/scene.dict -print_final_stats=1 corpus ../scenes ../tests/data/malformed 2>&1 | tail -15
cd ..
# The checkpoint reader: the container and the meta keys (engine/run/checkpoint_file.cpp).
ck_sources=(engine/run/checkpoint_file.cpp engine/core/errors.cpp)
if [ ! -x "$out/checkpoint_fuzzer" ] ||
   [ -n "$(find "${ck_sources[@]}" engine/run/checkpoint.hpp tests/fuzz/checkpoint_fuzzer.cpp -newer "$out/checkpoint_fuzzer")" ]; then
  "$cxx" -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
    -I. -I/usr/include/eigen3 tests/fuzz/checkpoint_fuzzer.cpp "${ck_sources[@]}" -o "$out/checkpoint_fuzzer"
fi
rm -rf "$out/ck_corpus" && mkdir -p "$out/ck_corpus" && cp tests/data/checkpoint_corpus/* "$out/ck_corpus/"
(cd "$out" && ./checkpoint_fuzzer -max_total_time="$(( (seconds + 1) / 2 ))" -timeout=10 -rss_limit_mb=2048 \
   -max_len=4096 -print_final_stats=1 ck_corpus 2>&1 | tail -8)
if [ "${2:-}" = "--merge" ]; then
  "$out/checkpoint_fuzzer" -merge=1 tests/data/checkpoint_corpus "$out/ck_corpus" 2>&1 | tail -2
  mkdir -p tests/data/fuzz_corpus
  "$out/scene_fuzzer" -merge=1 tests/data/fuzz_corpus "$out/corpus" 2>&1 | tail -2
fi
