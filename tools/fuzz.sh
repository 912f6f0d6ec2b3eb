#!/usr/bin/env bash
# Fuzzes the scene loader with libFuzzer (Debian's clang) for a bounded time:
#   bash tools/fuzz.sh [SECONDS] [--merge]
# Seeds: tests/data/fuzz_corpus (kept in the repository), scenes/ and the malformed corpus.
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
if [ "${2:-}" = "--merge" ]; then
  mkdir -p tests/data/fuzz_corpus
  "$out/scene_fuzzer" -merge=1 tests/data/fuzz_corpus "$out/corpus" 2>&1 | tail -2
fi
