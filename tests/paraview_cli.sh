#!/usr/bin/env bash
# ParaView (Debian's pvbatch, headless under xvfb-run) opens an sph-run output folder through
# frames.pvd: times, point counts, arrays and id order (tests/paraview_check.py); also
# after the run is resumed from a checkpoint into its own folder (the .pvd keeps the frames
# before the checkpoint with their times).
# Needs: tools/install_deps.sh --test (paraview, python3-paraview, xvfb).
set -uo pipefail
run=$1; src=$2
command -v pvbatch >/dev/null && command -v xvfb-run >/dev/null ||
  { echo "FAIL: pvbatch or xvfb-run missing: run 'bash tools/install_deps.sh --test' (as root)"; exit 1; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
"$run" "$src/scenes/dam_break.json" --end 0.2 --out "$tmp/run" -q --checkpoint-every 0.07 \
  --set 'output.attributes=["velocity","density","pressure"]' || fail=1
xvfb-run -a pvbatch "$src/tests/paraview_check.py" "$tmp/run" velocity,density,pressure || fail=1
cp "$tmp/run/frames.pvd" "$tmp/whole.pvd"
ck=$(ls "$tmp/run/checkpoints/"*.sphckpt | head -2 | tail -1)  # the one after 0.14 s
"$run" --resume "$ck" -q || fail=1
xvfb-run -a pvbatch "$src/tests/paraview_check.py" "$tmp/run" velocity,density,pressure || fail=1
cmp -s "$tmp/whole.pvd" "$tmp/run/frames.pvd" || { echo "FAIL: the resumed run's frames.pvd differs"; fail=1; }
# the surface meshes beside the particle frames
"$run" "$src/scenes/dam_break.json" --end 0.1 --format vtu,mesh --out "$tmp/surf" -q || fail=1
xvfb-run -a pvbatch "$src/tests/paraview_check.py" "$tmp/surf" velocity,density,pressure >"$tmp/surf.log" 2>&1 || fail=1
cat "$tmp/surf.log"
grep -q "^ParaView read 4 surface meshes" "$tmp/surf.log" || { echo "FAIL: ParaView did not read the 4 surface meshes"; fail=1; }
# individual stepping: its dt and active arrays
"$run" "$src/scenes/dam_break.json" --mode individual --end 0.1 --out "$tmp/ind" -q || fail=1
xvfb-run -a pvbatch "$src/tests/paraview_check.py" "$tmp/ind" velocity,density,pressure,dt,active || fail=1
[ $fail -eq 0 ] && echo "ParaView: all checks passed"
exit $fail
