#!/usr/bin/env bash
# sph-run misbehaving as the study tools' tests need it to (tests/sph_study.sh,
# resolution_study.sh, tools_plots.sh). Runs the real sph-run, $FAKE_REAL, with the same
# arguments, except for a run whose --out folder matches a rule of $FAKE_RULES, a
# space-separated list of GLOB:ACTION (the first match applies), e.g.
#   FAKE_RULES='*/02_individual:truncate-summary */reference:fail'
# Actions:
#   truncate-summary  run, then cut summary.json to its first 60 bytes; exit 0
#   truncate-probes   run, then cut every probes/*.csv in the middle of its sixth line; exit 0
#   no-probes         run, then remove probes/; exit 0
#   fail              exit 3 at once, as a simulation that failed
#   kill-tool         SIGKILL the tool that started this (a crash of the tool) before running
# Calls without --out (--list-modes) and runs no rule matches go to the real sph-run unchanged.
set -uo pipefail
set -f  # the rules' globs are patterns, not file names
out=""; prev=""
for a in "$@"; do
  [ "$prev" = --out ] && out=$a
  prev=$a
done
action=""
if [ -n "$out" ]; then
  for rule in ${FAKE_RULES:-}; do
    # shellcheck disable=SC2053  # the right side is a glob on purpose
    if [[ $out == ${rule%:*} ]]; then action=${rule##*:}; break; fi
  done
fi
case "$action" in
  "") exec "$FAKE_REAL" "$@" ;;
  fail) echo "fake sph-run: simulation failed (as asked)" >&2; exit 3 ;;
  kill-tool) kill -KILL "$PPID"; exit 137 ;;
esac
"$FAKE_REAL" "$@" || exit $?
case "$action" in
  truncate-summary)
    head -c 60 "$out/summary.json" > "$out/cut.tmp" && mv "$out/cut.tmp" "$out/summary.json" ;;
  truncate-probes)
    set +f
    for f in "$out"/probes/*.csv; do
      { head -n 5 "$f"; sed -n 6p "$f" | head -c 10; } > "$out/cut.tmp" && mv "$out/cut.tmp" "$f"
    done ;;
  no-probes) rm -rf "$out/probes" ;;
  *) echo "fake sph-run: unknown action '$action' in FAKE_RULES" >&2; exit 99 ;;
esac
exit 0
