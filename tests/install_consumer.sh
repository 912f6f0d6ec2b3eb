#!/usr/bin/env bash
# Installs the built tree into a temporary prefix, builds tools/example_consumer against it
# with find_package(sph), and runs it (it exits non-zero unless the fluid moved).
set -euo pipefail
build_dir=$1; source_dir=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cmake --install "$build_dir" --prefix "$tmp/prefix" >/dev/null
cmake -S "$source_dir/tools/example_consumer" -B "$tmp/build" -DCMAKE_PREFIX_PATH="$tmp/prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$tmp/build" >/dev/null
cd "$tmp" && ./build/example_consumer
