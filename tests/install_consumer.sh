#!/usr/bin/env bash
# Installs the built tree into a temporary prefix, builds tools/example_consumer against it
# with find_package(sph), and runs it (it exits non-zero unless the fluid moved); then runs the
# installed sph-run and sph-study from the prefix, with nothing on the library path (they find
# the engine's shared libraries through their RPATH), and checks that sph-study's modules and
# plot_dt.py went along.
set -euo pipefail
build_dir=$1; source_dir=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cmake --install "$build_dir" --prefix "$tmp/prefix" >/dev/null
if [ -x "$tmp/prefix/bin/sph-run" ]; then
  env -u LD_LIBRARY_PATH "$tmp/prefix/bin/sph-run" --version
  env -u LD_LIBRARY_PATH "$tmp/prefix/bin/sph-run" "$source_dir/scenes/dam_break.json" --list-modes -q >/dev/null
  for f in sph-study sph_python.py stepping_bound.py plot_dt.py; do
    [ -f "$tmp/prefix/bin/$f" ] || { echo "install: $f missing from $tmp/prefix/bin" >&2; exit 1; }
  done
  env -u LD_LIBRARY_PATH "$tmp/prefix/bin/sph-study" --help >/dev/null
fi
cmake -S "$source_dir/tools/example_consumer" -B "$tmp/build" -DCMAKE_PREFIX_PATH="$tmp/prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$tmp/build" >/dev/null
cd "$tmp" && ./build/example_consumer
