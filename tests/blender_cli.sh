#!/usr/bin/env bash
# Blender (Debian's blender, headless: blender -b) imports an sph-run folder with
# tools/blender/sph_import.py as one animated point cloud: vertex counts, attributes, id order,
# positions against the PLY files, the z-up axes, and the fluid surface as an animated mesh
# (closed, the fluid's volume) and a volume sequence of its .vdb level sets (tests/blender_check.py); and the saved .blend
# reopens with the object. Needs: tools/install_deps.sh --test.
set -uo pipefail
run=$1; src=$2
command -v blender >/dev/null || { echo "FAIL: blender missing: run 'bash tools/install_deps.sh --test' (as root)"; exit 1; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
"$run" "$src/scenes/dam_break.json" --end 0.2 --format ply,mesh,vdb --out "$tmp/run" -q || fail=1
blender -b --factory-startup --python-exit-code 1 --python "$src/tests/blender_check.py" -- \
  "$src/tools/blender/sph_import.py" "$tmp/run" >"$tmp/check.log" 2>&1; rc=$?
grep -E "^(FAIL|Blender imported)" "$tmp/check.log"
grep -q "^Blender imported 7 surface meshes and 7 level sets" "$tmp/check.log" ||
  { echo "FAIL: the surface was not imported (expected 7 meshes and 7 level sets)"; fail=1; }
[ $rc -eq 0 ] || { echo "FAIL: blender_check.py exited $rc"; tail -20 "$tmp/check.log"; fail=1; }
# A moving body (stirring_pool's paddle) becomes an animated object of its own.
"$run" "$src/scenes/stirring_pool.json" --end 0.1 --format ply --out "$tmp/pool" -q || fail=1
blender -b --factory-startup --python-exit-code 1 --python "$src/tests/blender_check.py" -- \
  "$src/tools/blender/sph_import.py" "$tmp/pool" >"$tmp/pool.log" 2>&1; rc=$?
grep -E "^(FAIL|Blender imported)" "$tmp/pool.log"
[ $rc -eq 0 ] || { echo "FAIL: blender_check.py (stirring_pool) exited $rc"; tail -20 "$tmp/pool.log"; fail=1; }
# The command-line form writes a .blend that holds the object and the importer.
blender -b --factory-startup --python-exit-code 1 --python "$src/tools/blender/sph_import.py" -- "$tmp/run" \
  --save "$tmp/run.blend" >/dev/null 2>&1 || { echo "FAIL: sph_import.py -- OUT --save"; fail=1; }
out=$(blender -b "$tmp/run.blend" --factory-startup --python-expr \
  'import bpy; o = bpy.data.objects["sph_fluid"]; print("BLEND", len(o.data.vertices), "sph_import.py" in bpy.data.texts)' 2>&1 | grep '^BLEND')
[ "$out" = "BLEND 8000 True" ] || { echo "FAIL: the saved .blend: '$out', expected 'BLEND 8000 True'"; fail=1; }
[ $fail -eq 0 ] && echo "Blender: all checks passed"
exit $fail
