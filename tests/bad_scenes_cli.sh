#!/usr/bin/env bash
# Every malformed scene of tests/data/malformed/ through sph-run: exit code 2, stderr is exactly
# "sph-run: error: " + the .expected message (with <file> replaced by the path given), and
# nothing is written: sph-run runs in an empty directory with the default output location
# (out/<scene name>/) and the directory must still be empty afterwards.
set -uo pipefail
run=$1; src=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
corpus=$src/tests/data/malformed
fail=0; n=0
for scene in "$corpus"/*.json; do
  n=$((n + 1))
  name=$(basename "$scene" .json)
  expected="sph-run: error: $(sed "s|<file>|$scene|g" "$corpus/$name.expected")"
  work=$tmp/work_$name; mkdir -p "$work"
  (cd "$work" && "$run" "$scene" -q) >"$tmp/out" 2>"$tmp/err"; rc=$?
  got=$(cat "$tmp/err")
  if [ $rc -ne 2 ]; then echo "FAIL $name: exit code $rc, expected 2"; fail=1; fi
  if [ "$got" != "$expected" ]; then
    echo "FAIL $name: message differs"; echo "  expected: $expected"; echo "  got:      $got"; fail=1
  fi
  if [ -n "$(ls -A "$work")" ]; then echo "FAIL $name: files left behind: $(ls -A "$work")"; fail=1; fi
  rm -rf "$work"
done
if [ "$n" -lt 40 ]; then echo "FAIL: only $n malformed scenes (at least 40 expected)"; fail=1; fi
[ $fail -eq 0 ] && echo "bad scenes: all $n exit 2 with their exact message and leave no file"
exit $fail
