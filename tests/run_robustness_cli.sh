#!/usr/bin/env bash
# sph-run as careless and hostile users run it (issue 18): signals, folders two runs share,
# outputs the environment refuses, inputs that never end, crafted checkpoints, command-line
# habits. Each check reproduces a defect that was measured before it was fixed.
set -uo pipefail
run=$1; src=$2
tmp=$(mktemp -d); trap 'chmod -R u+w "$tmp" 2>/dev/null; rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
fail=0
check() { if ! eval "$2"; then echo "FAIL: $1"; fail=1; else echo "ok: $1"; fi; }
scene=$src/scenes/dam_break.json
json() { python3 -c "import json,sys; s=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
wait_for() { for _ in $(seq 1 600); do [ -e "$1" ] && return 0; sleep 0.05; done; return 1; }

# 1. SIGTERM: the run stops after the step in progress, writes a final checkpoint and its
#    summary (marked interrupted) and exits 128 + 15; the checkpoint continues the run to its end.
"$run" "$scene" --end 3 --out sig --checkpoint-every 0.05 --no-frames -q 2>sig.err & pid=$!
wait_for sig/checkpoints/checkpoint_000126.sphckpt; kill -TERM $pid; wait $pid; rc=$?
check "SIGTERM exits 143 (got $rc)" '[ $rc -eq 143 ]'
check "the message names the signal and the checkpoint to resume" 'grep -q "stopped by SIGTERM at t = .*continue with: sph-run --resume sig/checkpoints/checkpoint_" sig.err'
check "summary.json is marked interrupted by SIGTERM before the end" '[ "$(json sig/summary.json "s[\"interrupted\"][\"by\"]")" = SIGTERM ] && json sig/summary.json "1 if s[\"simulated_time_s\"] < 3 else exit(1)" >/dev/null'
steps=$(json sig/summary.json 's["steps"]')
check "stats.csv holds every step of the interrupted run ($steps)" '[ $(( $(wc -l < sig/stats.csv) - 1 )) -eq "$steps" ]'
last=$(printf 'sig/checkpoints/checkpoint_%06d.sphckpt' "$steps")
check "a final checkpoint at the last step ($last)" '[ -s "$last" ]'
"$run" --resume "$last" --end 0 -q 2>/dev/null; rc=$?
check "a resumed run takes no scene options (exit 2, got $rc)" '[ $rc -eq 2 ]'

# 2. A second signal stops at once (no graceful message): the run is stopped (SIGSTOP) while
#    SIGINT and SIGTERM are queued, so both arrive together when it continues (perhaps on two
#    threads at once); the first is handled, the second kills it (exit 130 or 143, no summary
#    rewritten and no graceful message). Job control on: a script's background job ignores
#    SIGINT otherwise (and sph-run keeps a signal its parent ignores).
set -m
"$run" "$scene" --end 3 --out sig2 --no-frames -q 2>sig2.err & pid=$!
set +m
wait_for sig2/run.json; sleep 0.3
kill -STOP $pid; kill -INT $pid; kill -TERM $pid; kill -CONT $pid; wait $pid; rc=$?
check "SIGINT then SIGTERM: the second stops at once (exit 130/143, no graceful message; got $rc)" '[ $rc -eq 143 -o $rc -eq 130 ] && ! grep -q "stopped by" sig2.err && [ ! -e sig2/summary.json ]'
set -m
"$run" "$scene" --end 3 --out sig3 --no-frames -q 2>sig3.err & pid=$!
set +m
wait_for sig3/run.json; sleep 0.3; kill -INT $pid; wait $pid; rc=$?
check "one SIGINT from a terminal: graceful stop, exit 130 (got $rc)" '[ $rc -eq 130 ] && grep -q "stopped by SIGINT" sig3.err && [ "$(json sig3/summary.json "s[\"interrupted\"][\"by\"]")" = SIGINT ]'

# 3. Folders: a shorter run into an old folder replaces its outputs (before: frames 4-6 of the old
#    run stayed beside frames 0-3 of the new one and summary.json said 4).
"$run" "$scene" --end 0.2 --out f -q && "$run" "$scene" --end 0.1 --out f -q; rc=$?
check "second run into the same folder exits 0 (got $rc)" '[ $rc -eq 0 ]'
check "only the second run's 4 frames remain" '[ "$(ls f/frames/frame_*.vtu | wc -l)" -eq 4 ] && [ ! -e f/frames/frame_00004.vtu ]'
check "stats.csv rows match the second run's summary" '[ $(( $(wc -l < f/stats.csv) - 1 )) -eq "$(json f/summary.json "s[\"steps\"]")" ]'
check "run.json names the run and the scene" '[ "$(json f/run.json "s[\"scene\"]")" = dam_break ] && [ "$(json f/run.json "len(s[\"run_id\"])")" -eq 16 ]'
mkdir -p foreign/frames && touch foreign/stats.csv foreign/frames/frame_00009.vtu foreign/notes.txt
"$run" "$scene" --end 0.02 --out foreign -q 2>foreign.err; rc=$?
check "outputs no run.json claims are refused (exit 2, got $rc) naming --force" '[ $rc -eq 2 ] && grep -q "no sph-run run claims (no run.json); pass --force" foreign.err && [ -e foreign/frames/frame_00009.vtu ]'
"$run" "$scene" --end 0.02 --out foreign --force -q; rc=$?
check "--force replaces them and keeps other files (exit $rc)" '[ $rc -eq 0 ] && [ ! -e foreign/frames/frame_00009.vtu ] && [ -e foreign/notes.txt ]'
"$run" "$scene" --end 3 --out busy --no-frames -q & pid=$!
wait_for busy/run.json; sleep 0.3
"$run" "$scene" --end 0.02 --out busy -q 2>busy.err; rc=$?
kill -KILL $pid; wait $pid 2>/dev/null
check "a folder another live run writes to is refused (exit 2, got $rc)" '[ $rc -eq 2 ] && grep -q "is writing to this folder" busy.err'
"$run" --resume "$last" --out f -q 2>resume.err; rc=$?
check "resuming into another run's folder is refused (exit 2, got $rc)" '[ $rc -eq 2 ] && grep -q "holds the outputs of run .* the checkpoint belongs to run" resume.err'

# 4. Outputs the environment refuses: exit 2 (bad input) or 5 (environment), with the path and
#    the reason, before the simulation starts (before: exit 4 "internal error").
touch afile
"$run" "$scene" --out afile -q 2>e1; rc=$?
check "--out a file: exit 2 naming it (got $rc)" '[ $rc -eq 2 ] && grep -q "afile: is a file, expected a folder" e1'
"$run" "$scene" --out /proc/sph_out -q 2>e2; rc=$?
check "--out where no folder can be made: exit 5 with the reason (got $rc)" '[ $rc -eq 5 ] && grep -q "/proc/sph_out: cannot create the output folder (" e2'
mkdir cwd && (cd cwd && "$run" "$scene" -q --set "name=$(printf 'n%.0s' $(seq 300))" 2>../e3); rc=$?
check "a 300-character scene name: exit 2, nothing written (got $rc)" '[ $rc -eq 2 ] && grep -q "is 300 bytes, more than the file system" e3 && [ -z "$(ls -A cwd)" ]'
long=$(printf 'p%.0s' $(seq 251))
"$run" "$scene" --end 0.01 --no-frames -q --out p251 --set "probes=[{\"type\":\"front\",\"name\":\"$long\",\"method\":\"neighbours\"}]"; rc=$?
check "a 251-character probe name runs (the temporary file name no longer grows it; exit $rc)" '[ $rc -eq 0 ] && [ -s "p251/probes/$long.csv" ]'
"$run" "$scene" --end 0.01 -q --out p252 --set "probes=[{\"type\":\"front\",\"name\":\"p$long\",\"method\":\"neighbours\"}]" 2>e4; rc=$?
check "a 252-character probe name: exit 2 naming the key (got $rc)" '[ $rc -eq 2 ] && grep -q "/probes/0/name" e4 && [ ! -e p252 ]'

# 4b. A full disk (a tmpfs of 5.3 MiB; needs root, as CI runs): with --no-frames the run keeps its
#    rows in memory and the first commit of 4 MiB fails. Before: exit 5 and an empty folder after
#    the whole simulation. Now: what was computed is saved into the 5 MiB reserve the run made at
#    its start: stats.csv to the failing step, summary.json marked output_failed, the probes.
mkdir full && if mount -t tmpfs -o size=5400k tmpfs full 2>/dev/null; then
  trap 'umount "$tmp/prev/frames" "$tmp/full" 2>/dev/null; chmod -R u+w "$tmp" 2>/dev/null; rm -rf "$tmp"' EXIT
  "$run" "$scene" --scale 0.05 --end 25 --no-frames -q --out full/run 2>e_full; rc=$?
  check "disk full: exit 5 naming the file and the reason (got $rc)" '[ $rc -eq 5 ] && grep -q "full/run/stats.csv: .*(No space left on device)" e_full'
  check "disk full: the message lists what was saved" 'grep -q "saved before stopping: stats.csv: complete to t = " e_full && grep -q "saved before stopping: summary.json: written" e_full'
  steps=$(json full/run/summary.json 's["steps"]' 2>/dev/null)
  check "disk full: summary.json says output_failed at step $steps" '[ -n "$steps" ] && [ "$(json full/run/summary.json "s[\"output_failed\"][\"step\"]")" = "$steps" ]'
  check "disk full: stats.csv holds every one of its $steps steps, whole rows" '[ $(( $(wc -l < full/run/stats.csv) - 1 )) -eq "$steps" ] && [ "$(tail -c 1 full/run/stats.csv | od -An -c | tr -d " ")" = "\n" ] && [ "$steps" -gt 15000 ]'
  check "disk full: probes saved, no reserve or temporary file left" '[ -s full/run/probes/front.csv ] && [ ! -e full/run/.sph-reserve ] && [ -z "$(find full -name ".sph.tmp*")" ]'
  rm -rf full/run
  # The simulation fails (a NaN injected at step 400) on a disk with room for the reserve and
  # 80 KiB more: the failed run's records do not fit, so they go into the reserve as above,
  # marked failed and output_failed.
  head -c 200K /dev/zero > full/filler
  "$run" "$scene" --scale 0.5 --end 0.5 --no-frames -q --inject-nan 400:5 --out full/nan 2>e_fullnan; rc=$?
  check "disk full when a run fails: exit 3, its records saved from the reserve (got $rc)" \
    '[ $rc -eq 3 ] && grep -q "saved before stopping: summary.json: written" e_fullnan && [ "$(json full/nan/summary.json "s[\"failed\"][\"step\"]")" = 400 ] && [ -n "$(json full/nan/summary.json "s[\"output_failed\"][\"reason\"]")" ] && [ $(( $(wc -l < full/nan/stats.csv) - 1 )) -ge 400 ] && [ -s full/nan/probes/front.csv ] && [ ! -e full/nan/.sph-reserve ]'
  rm -rf full/nan full/filler
  # Not even room for the reserve: refused before the simulation starts, the folder left clean.
  head -c 1M /dev/zero > full/filler
  "$run" "$scene" --end 0.01 -q --out full/run2 2>e_noroom; rc=$?
  check "no room for the reserve: exit 5 before the run (got $rc)" '[ $rc -eq 5 ] && grep -q "no room for the 5 MiB the run keeps" e_noroom && [ ! -e full/run2 ]'
  # Room for the reserve but not for scene_as_run.json (glass's, 126 kB with its mesh inline):
  # exit 5 before the run, the reserve removed and the folder left clean.
  rm -f full/filler && head -c 220K /dev/zero > full/filler
  "$run" "$src/scenes/glass.json" --end 0.01 -q --out full/run3 2>e_noscene; rc=$?
  check "no room for scene_as_run.json: exit 5 naming it, no folder left (got $rc)" '[ $rc -eq 5 ] && grep -q "scene_as_run.json" e_noscene && [ ! -e full/run3 ]'
  umount full
else
  echo "FAIL: cannot mount a tmpfs (the disk-full checks need root)"; fail=1
fi

# 4c. Replacing an earlier run's outputs is all or nothing: with its frames/ a read-only mount (it
# cannot be moved or emptied), a fresh run into the folder exits 5 naming it and every output of
# the earlier run is still there.
"$run" "$scene" --scale 0.5 --end 0.01 -q --out prev 2>/dev/null
ls -A prev | sort > prev.before
if mount --bind prev/frames prev/frames 2>/dev/null && mount -o remount,ro,bind prev/frames 2>/dev/null; then
  "$run" "$scene" --scale 0.5 --end 0.01 -q --set fluid.viscosity=0.2 --out prev 2>e_prev; rc=$?
  check "an earlier run's outputs that cannot all be removed: exit 5 naming frames/, none removed (got $rc)" \
    '[ $rc -eq 5 ] && grep -q "prev/frames: cannot remove the earlier run.s output" e_prev && [ "$(ls -A prev | sort)" = "$(cat prev.before)" ] && [ -s prev/stats.csv ] && [ -s prev/summary.json ]'
  umount prev/frames
else
  echo "FAIL: cannot make a read-only bind mount (the all-or-nothing check needs root, as CI runs)"; fail=1
fi
rm -rf prev

# 5. Inputs that never end or are too deep: refused at once.
mkfifo fifo
timeout 20 "$run" fifo -q 2>e5; rc=$?
check "a FIFO as scene: exit 2 at once (got $rc)" '[ $rc -eq 2 ] && grep -q "device, pipe or socket" e5'
timeout 20 "$run" --resume /dev/zero 2>e6; rc=$?
check "--resume /dev/zero: exit 2 (got $rc)" '[ $rc -eq 2 ] && grep -q "/dev/zero: is not a regular file" e6'
timeout 20 "$run" --resume "$tmp" 2>e7; rc=$?
check "--resume a folder: exit 2 (got $rc)" '[ $rc -eq 2 ] && grep -q "is not a regular file" e7'
python3 -c "print('{\"a\":' + '[' * 100000 + ']' * 100000 + '}')" > deep.json
timeout 20 "$run" deep.json 2>e8; rc=$?
check "10^5-deep JSON: exit 2 naming the depth (got $rc)" '[ $rc -eq 2 ] && grep -q "nested more than 64 deep" e8'
timeout 20 "$run" --resume "$src/tests/data/checkpoint_corpus/missing_t.sphckpt" 2>e9; rc=$?
check "a checkpoint without meta key t: exit 2 naming the file and key (got $rc)" '[ $rc -eq 2 ] && grep -q "missing_t.sphckpt: meta key .t. is missing" e9'

# 6. Command-line habits.
"$run" --set simulation.frame_rate=10 "$scene" --end 0.2 --out habits -q; rc=$?
check "--set before the scene path takes one value (exit $rc; before: the scene became a --set value)" '[ $rc -eq 0 ] && [ "$(ls habits/frames/frame_*.vtu | wc -l)" -eq 3 ]'
"$run" "$scene" --end 0.1 --frame-rate 20 --format ply,vtu --out habits2 >h2 2>&1; rc=$?
check "--frame-rate and --format (exit $rc)" '[ $rc -eq 0 ] && [ -s habits2/frames/frame_00002.ply ] && [ -s habits2/frames/frame_00002.vtu ] && [ ! -e habits2/frames/frame_00003.ply ]'
check "the last line says how many frames of which formats went where" 'grep -q "wrote 3 frame(s) (ply, vtu) to habits2/frames" h2'
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); d['simulation']['end_time']='abc'; json.dump(d, open('abc.json','w'))" "$scene"
"$run" abc.json --end 0.01 --out abc -q 2>e10; rc=$?
check "a scene value --end replaces is still checked (exit 2; before: ran, exit 0; got $rc)" '[ $rc -eq 2 ] && grep -q "abc.json: /simulation/end_time: found \"abc\".*the file.s own value must be valid too" e10 && [ ! -e abc ]'
"$run" "$src/scenes/glass.json" --set 'simulation.gravity=[0,-1e12,0]' --end 0.01 --out g -q 2>e11; rc=$?
check "a step collapse before any particle exists names the scene's figures, no particle (exit 3; before: \"acceleration 0 m/s^2 at particle 0\"; got $rc)" '[ $rc -eq 3 ] && grep -q "from system .pcisph_dt. .*there is no fluid particle yet.*gravity 1e+12 m/s^2" e11 && ! grep -q "at particle" e11'
help=$("$run" --help)
check "--help lists the exit codes and the output layout" '[[ "$help" == *"5 an output could not be written"* && "$help" == *"run.json"* && "$help" == *"--format"* ]]'

[ $fail -eq 0 ] && echo "sph-run robustness: all checks passed"
exit $fail
