#!/usr/bin/env bash
# sph-run outputs under interruption (issue 6): determinism, checkpoints, resume, atomic files.
#  1. Determinism: the same scene twice with the same thread count gives byte-identical
#     frames and stats.csv (without its wall-clock columns, wall_s and ms_*).
#  2. SIGKILL in the middle of a run (after its first checkpoint, while it is writing frames
#     and rows): every file left is complete and readable (each frame parses with all its
#     arrays, stats.csv holds whole rows only, no temporary file is left).
#  3. --resume from the last checkpoint the killed run left completes it, and its frames,
#     stats.csv rows and probe series equal the uninterrupted run's byte for byte (also when
#     resumed into a new directory: the checkpoint carries the probe series).
#  4. A damaged, truncated or wrong-version checkpoint, --resume with a scene, or a resume into
#     a folder whose stats.csv has other columns, exits 2 with the reason.
set -uo pipefail
run=$1; src=$2
tmp=$(mktemp -d); trap 'kill -9 $pid 2>/dev/null; rm -rf "$tmp"' EXIT
pid=0; fail=0
# A python with numpy (tools/install_deps.sh installs Debian's; a pyenv python first on PATH
# may lack it).
py=""
for c in python3 /usr/bin/python3; do
  if "$c" -c "import numpy" 2>/dev/null; then py=$c; break; fi
done
if [ -z "$py" ]; then echo "FAIL: no python3 with numpy (run: bash tools/install_deps.sh)"; exit 1; fi
check() { if ! eval "$2"; then echo "FAIL: $1"; fail=1; else echo "ok: $1"; fi; }
scene=$src/scenes/dam_break.json
# Scale 2 (16,000 particles, about 1.5 s on 2 cores): long enough that the SIGKILL below lands mid-run.
args=(--scale 2 --end 0.2 --threads 2 --checkpoint-every 0.05 -q)
# stats.csv without its wall-clock columns (wall_s and ms_<system>), picked by name: every other
# column, the counters a recipe adds included, must match.
physics() { awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) keep[i] = ($i != "wall_s" && $i !~ /^ms_/) }
  { out = ""; for (i = 1; i <= NF; ++i) if (keep[i]) out = out (out == "" ? "" : ",") $i; print out }' "$1"; }
same_frames() {  # same_frames DIR_A DIR_B: same frame files, byte-identical
  [ "$(cd "$1/frames" && ls)" = "$(cd "$2/frames" && ls)" ] || return 1
  for f in "$1"/frames/*; do cmp -s "$f" "$2/frames/$(basename "$f")" || { echo "  differs: $(basename "$f")"; return 1; }; done
}

# 1. Determinism.
"$run" "$scene" "${args[@]}" --out "$tmp/a"; rc_a=$?
"$run" "$scene" "${args[@]}" --out "$tmp/a2"; rc_a2=$?
check "two uninterrupted runs exit 0 (got $rc_a, $rc_a2)" '[ $rc_a -eq 0 ] && [ $rc_a2 -eq 0 ]'
nframes=$(ls "$tmp/a/frames" | wc -l)
check "the run wrote 7 frames (t = 0 to 0.2 s at 30 fps; got $nframes) and 3 checkpoints" \
  '[ "$nframes" -eq 7 ] && [ "$(ls "$tmp/a/checkpoints" | wc -l)" -eq 3 ]'
check "same scene, same threads: identical stats.csv physics columns" 'cmp -s <(physics "$tmp/a/stats.csv") <(physics "$tmp/a2/stats.csv")'
check "same scene, same threads: byte-identical frames" 'same_frames "$tmp/a" "$tmp/a2"'

# 2. SIGKILL mid-run, once the first checkpoint exists.
"$run" "$scene" "${args[@]}" --out "$tmp/k" & pid=$!
for _ in $(seq 1 600); do
  [ -n "$(ls "$tmp/k/checkpoints" 2>/dev/null)" ] && break
  kill -0 $pid 2>/dev/null || break
  sleep 0.05
done
sleep 0.3
kill -9 $pid 2>/dev/null; killed=$?; wait $pid 2>/dev/null
check "the run was killed while running" '[ $killed -eq 0 ]'
# A kill in the moment between naming a finished file and renaming it (AtomicFile::commit) can
# leave that one hidden temporary; never more, and the resume below removes it.
check "at most one temporary file left" '[ "$(find "$tmp/k" -name "*.tmp*" | wc -l)" -le 1 ]'
check "every file left is complete and readable" '"$py" - "$tmp/k" "$src/tools" <<PY
import json, pathlib, sys
sys.path.insert(0, sys.argv[2])
from sph_vtu import read_vtu
d = pathlib.Path(sys.argv[1])
frames = sorted((d / "frames").glob("*.vtu"))
assert frames, "no frame"
n0 = read_vtu(frames[0]).n
for f in frames:
    fr = read_vtu(f)
    assert fr.n == n0, f"{f}: {fr.n} points, expected {n0}"
    for name, a in fr.point_data.items():
        assert len(a) == fr.n, f"{f}: {name} has {len(a)} values"
text = (d / "stats.csv").read_text()
assert text.endswith("\n"), "stats.csv ends inside a row"
rows = text.splitlines()
assert len({r.count(",") for r in rows}) == 1, "stats.csv rows of different lengths"
steps = [int(r.split(",")[0]) for r in rows[1:]]
assert steps == list(range(len(steps))), "stats.csv rows are not steps 0..n-1"
if (d / "summary.json").exists():
    json.loads((d / "summary.json").read_text())
ck = len(list((d / "checkpoints").iterdir()))
print(f"  killed run left {len(frames)} frames, {len(steps)} stats rows, {ck} checkpoint(s)")
PY'

# 3. Resume the killed run from its last checkpoint (into its own directory).
last=$(ls "$tmp/k/checkpoints" | tail -1)
"$run" --resume "$tmp/k/checkpoints/$last" -q; rc=$?
check "resume from $last exits 0 (got $rc)" '[ $rc -eq 0 ]'
check "no temporary file left after the resume" '[ -z "$(find "$tmp/k" -name "*.tmp*")" ]'
check "resumed run: stats.csv physics columns equal the uninterrupted run's" 'cmp -s <(physics "$tmp/a/stats.csv") <(physics "$tmp/k/stats.csv")'
check "resumed run: frames byte-identical to the uninterrupted run's" 'same_frames "$tmp/a" "$tmp/k"'
same_probes() {  # same_probes DIR_A DIR_B: same probe series, byte-identical (the whole run's)
  [ -n "$(ls "$1/probes")" ] && [ "$(cd "$1/probes" && ls)" = "$(cd "$2/probes" && ls)" ] || return 1
  for f in "$1"/probes/*; do cmp -s "$f" "$2/probes/$(basename "$f")" || { echo "  differs: $(basename "$f")"; return 1; }; done
}
check "resumed run: probes/*.csv byte-identical to the uninterrupted run's (samples before the checkpoint kept)" \
  'same_probes "$tmp/a" "$tmp/k"'
check "resumed run: summary physics equal" '"$py" -c "
import json, sys
a = json.load(open(\"$tmp/a/summary.json\")); k = json.load(open(\"$tmp/k/summary.json\"))
keys = [\"steps\", \"simulated_time_s\", \"min_dt_s\", \"max_dt_s\", \"max_density_error\", \"boundary_collisions_total\", \"front_x_m\", \"frames\"]
sys.exit(0 if all(a[x] == k[x] for x in keys) else 1)"'
# Resuming into a new directory: stats.csv starts at the checkpoint's step, later frames equal.
first=$(ls "$tmp/a/checkpoints" | head -1)
"$run" --resume "$tmp/a/checkpoints/$first" --out "$tmp/b" -q; rc=$?
check "resume into a new --out exits 0 (got $rc)" '[ $rc -eq 0 ]'
check "its frames equal the uninterrupted run's" 'for f in "$tmp"/b/frames/*; do cmp -s "$f" "$tmp/a/frames/$(basename "$f")" || exit 1; done'
check "its stats.csv rows are the uninterrupted run's from the checkpoint on" \
  '[ "$(physics "$tmp/b/stats.csv" | tail -n +2)" = "$(physics "$tmp/a/stats.csv" | tail -n +$(( 10#${first//[^0-9]/} + 2 )))" ]'
check "its probes/*.csv are the whole run's (the checkpoint carries the series)" 'same_probes "$tmp/a" "$tmp/b"'
check "its frames.pvd lists exactly the frames it holds, and summary.json counts them" '"$py" - "$tmp/b" <<PY
import json, pathlib, re, sys
d = pathlib.Path(sys.argv[1])
listed = re.findall(r"file=\"(frames/frame_\\d+\\.vtu)\"", (d / "frames.pvd").read_text())
held = sorted("frames/" + f.name for f in (d / "frames").iterdir())
print("  listed", listed, "held", held)
sys.exit(0 if listed == held and len(held) > 0 and json.load(open(d / "summary.json"))["frames"] == len(held) else 1)
PY'
# Resuming from another working directory: the checkpoint names the run's folder and scene by
# absolute paths, so the run continues in its own folder (not in a new one under the cwd).
# A run started with relative paths (scene and --out), resumed from a sibling folder.
mkdir -p "$tmp/elsewhere" && cp "$scene" "$tmp/rel.json"
(cd "$tmp" && "$run" rel.json --end 0.02 --checkpoint-every 0.01 --no-frames --out rel -q); rc=$?
cp "$tmp/rel/stats.csv" "$tmp/rel.stats.csv"
ck_rel=$(ls "$tmp/rel/checkpoints" | head -1)
(cd "$tmp/elsewhere" && "$run" --resume "../rel/checkpoints/$ck_rel" -q); rc2=$?
check "resume from another working directory continues in the run's own folder (got $rc, $rc2)" \
  '[ $rc -eq 0 ] && [ $rc2 -eq 0 ] && [ -z "$(ls -A "$tmp/elsewhere")" ] && cmp -s <(physics "$tmp/rel.stats.csv") <(physics "$tmp/rel/stats.csv")'

# 4. Bad checkpoints.
ck=$tmp/a/checkpoints/$first
"$py" -c "import sys; b = bytearray(open('$ck','rb').read()); b[len(b)//2] ^= 1; open('$tmp/corrupt.sphckpt','wb').write(b)"
"$run" --resume "$tmp/corrupt.sphckpt" --out "$tmp/c1" 2>"$tmp/e1"; rc=$?
check "corrupt checkpoint exits 2 naming the checksum (got $rc)" '[ $rc -eq 2 ] && grep -q "corrupt.sphckpt: checksum mismatch" "$tmp/e1" && [ ! -e "$tmp/c1" ]'
"$py" -c "b = bytearray(open('$ck','rb').read()); b[8] = 7; open('$tmp/v7.sphckpt','wb').write(b)"
"$run" --resume "$tmp/v7.sphckpt" --out "$tmp/c2" 2>"$tmp/e2"; rc=$?
check "wrong-version checkpoint exits 2 (got $rc)" '[ $rc -eq 2 ] && grep -q "v7.sphckpt: checkpoint format version 7, expected version 2" "$tmp/e2"'
head -c 1000 "$ck" > "$tmp/short.sphckpt"
"$run" --resume "$tmp/short.sphckpt" --out "$tmp/c3" 2>"$tmp/e3"; rc=$?
check "truncated checkpoint exits 2 (got $rc)" '[ $rc -eq 2 ] && grep -q "(truncated?)" "$tmp/e3"'
"$run" "$scene" --resume "$ck" --out "$tmp/c4" 2>"$tmp/e4"; rc=$?
check "--resume with a scene exits 2 (got $rc)" '[ $rc -eq 2 ] && grep -q "expected none" "$tmp/e4"'
# A folder whose stats.csv has other columns (an older engine's, say): refused before anything is
# appended, the file left as it was.
# (Its scene_as_run.json, marked here as another run's, is left as it was too.)
cp -r "$tmp/a" "$tmp/c5"; sed -i '1s/,v_mean,/,v_avg,/' "$tmp/c5/stats.csv"; cp "$tmp/c5/stats.csv" "$tmp/c5.before"
echo '{"name": "another run"}' > "$tmp/c5/scene_as_run.json"; cp "$tmp/c5/run.json" "$tmp/c5.run.json"
"$run" --resume "$tmp/c5/checkpoints/$first" --out "$tmp/c5" -q 2>"$tmp/e5"; rc=$?
check "resume into a folder whose stats.csv has other columns exits 2 naming it, the folder's files untouched, no reserve left (got $rc)" \
  '[ $rc -eq 2 ] && grep -q "c5/stats.csv: its columns differ" "$tmp/e5" && cmp -s "$tmp/c5/stats.csv" "$tmp/c5.before" && [ ! -e "$tmp/c5/.sph-reserve" ] && grep -q "another run" "$tmp/c5/scene_as_run.json" && cmp -s "$tmp/c5/run.json" "$tmp/c5.run.json"'
# Another run's folder (its run.json names another id) whose stats.csv has other columns: with
# --force the resume replaces its outputs (checkpoints kept) and runs to the end.
cp -r "$tmp/a" "$tmp/c8"; sed -i '1s/,v_mean,/,v_avg,/' "$tmp/c8/stats.csv"
"$py" -c "import json; m = json.load(open('$tmp/c8/run.json')); m['run_id'] = '0123456789abcdef'; json.dump(m, open('$tmp/c8/run.json', 'w'))"
"$run" --resume "$tmp/c8/checkpoints/$first" --out "$tmp/c8" -q 2>"$tmp/e8"; rc=$?
"$run" --resume "$tmp/c8/checkpoints/$first" --out "$tmp/c8" -q --force 2>"$tmp/e8f"; rc2=$?
check "resume into another run's folder: refused without --force, with it the outputs replaced and the run completed (got $rc, $rc2)" \
  '[ $rc -eq 2 ] && grep -q "holds the outputs of run 0123456789abcdef" "$tmp/e8" && [ $rc2 -eq 0 ] && head -1 "$tmp/c8/stats.csv" | grep -q ",v_mean," && [ -s "$tmp/c8/summary.json" ]'
# A stats.csv shorter than the checkpoint's (another run's folder): refused, and the 5 MiB reserve
# the run made before reading it removed.
cp -r "$tmp/a" "$tmp/c6"; head -n 3 "$tmp/a/stats.csv" > "$tmp/c6/stats.csv"
"$run" --resume "$tmp/c6/checkpoints/$first" --out "$tmp/c6" -q 2>"$tmp/e6"; rc=$?
check "resume into a folder whose stats.csv is shorter than the checkpoint's exits 2 naming it, no reserve left (got $rc)" \
  '[ $rc -eq 2 ] && grep -q "c6/stats.csv: holds .* bytes, expected at least the" "$tmp/e6" && [ ! -e "$tmp/c6/.sph-reserve" ]'
# Outputs no run.json claims (another program's, or a run whose marker was deleted): a resume
# would append to them and list their frames; refused unless --force, nothing changed.
cp -r "$tmp/a" "$tmp/c7"; rm "$tmp/c7/run.json"; cp "$tmp/c7/stats.csv" "$tmp/c7.before"
"$run" --resume "$tmp/c7/checkpoints/$first" --out "$tmp/c7" -q 2>"$tmp/e7"; rc=$?
check "resume into a folder of unclaimed outputs exits 2 naming them, nothing changed (got $rc)" \
  '[ $rc -eq 2 ] && grep -q "c7: holds outputs (.*stats.csv.*) that no sph-run run claims (no run.json), the checkpoint belongs to run" "$tmp/e7" && cmp -s "$tmp/c7/stats.csv" "$tmp/c7.before" && [ ! -e "$tmp/c7/run.json" ] && [ ! -e "$tmp/c7/.sph-reserve" ]'

[ $fail -eq 0 ] && echo "checkpoints, resume, SIGKILL and determinism: all checks passed"
exit $fail
