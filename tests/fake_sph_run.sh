#!/usr/bin/env bash
# sph-run misbehaving as the study tools' tests need it to (tests/sph_study.sh,
# resolution_study.sh, tools_plots.sh). Runs the real sph-run, $FAKE_REAL, with the same
# arguments, except for a run whose --out folder matches a rule of $FAKE_RULES, a
# space-separated list of GLOB:ACTION (the first match applies), e.g.
#   FAKE_RULES='*/02_individual:truncate-summary */reference:fail'
# Actions:
#   truncate-summary  run, then cut summary.json to its first 60 bytes; exit 0
#   truncate-probes   run, then cut every probes/*.csv inside the first cell of its sixth line
#                     (half that cell, no newline); exit 0
#   no-probes         run, then remove probes/; exit 0
#   interrupted       run, then mark summary.json "interrupted" by SIGTERM and exit 143, as
#                     sph-run stopped by SIGTERM does
#   fail              exit 3 at once, as a simulation that failed
#   kill-tool         SIGKILL the tool that started this (a crash of the tool) before running
#   int-tool          SIGINT the tool that started this (Ctrl-C), then wait (sleep 30) for the
#                     tool to end this process; its pid goes to $FAKE_PIDFILE if set
#   int-group         run, then SIGINT the tool's whole process group, as a terminal's Ctrl-C
#                     does (the tool must lead its group: start it with `setsid --wait`; refused,
#                     exit 99, otherwise, so that a test runner is never signalled), and then do
#                     what sph-run does: the first SIGINT or SIGTERM lets the step in progress
#                     finish (here 2 s, or until a second signal), then summary.json is marked
#                     "interrupted" by it and the exit is 128 + it; a second signal stops at once
#                     (no stats.csv, no summary.json). The signals it got, in order, go to
#                     <out>/fake_signals ("TERM": the tool forwarded one SIGTERM and nothing else
#                     reached the run; "INT TERM": the terminal's SIGINT reached it too)
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
  int-tool) echo $$ > "${FAKE_PIDFILE:-/dev/null}"; kill -INT "$PPID"; exec sleep 30 ;;
esac
"$FAKE_REAL" "$@" || exit $?
case "$action" in
  truncate-summary)
    head -c 60 "$out/summary.json" > "$out/cut.tmp" && mv "$out/cut.tmp" "$out/summary.json" ;;
  truncate-probes)
    set +f
    for f in "$out"/probes/*.csv; do
      line=$(sed -n 6p "$f"); cell=${line%%,*}
      { head -n 5 "$f"; printf '%s' "${cell:0:$(( (${#cell} + 1) / 2 ))}"; } > "$out/cut.tmp" && mv "$out/cut.tmp" "$f"
    done ;;
  no-probes) rm -rf "$out/probes" ;;
  int-group)
    stat=$(cat "/proc/$PPID/stat"); stat=${stat##*) }; read -r _ _ group _ <<< "$stat"
    if [ "$group" != "$PPID" ]; then
      echo "fake sph-run: int-group: the tool ($PPID) does not lead its process group ($group): start it with setsid --wait" >&2
      exit 99
    fi
    got=()
    trap 'got+=(INT)' INT
    trap 'got+=(TERM)' TERM
    kill -INT -- "-$group"
    for _ in $(seq 40); do [ ${#got[@]} -ge 2 ] && break; sleep 0.05; done
    echo "${got[*]}" > "$out/fake_signals"
    case ${#got[@]} in
      0) exit 0 ;;
      1) /usr/bin/python3 -c 'import json, sys
s = json.load(open(sys.argv[1])); s["interrupted"] = {"by": "SIG" + sys.argv[2], "t": s["simulated_time_s"], "step": s["steps"]}
json.dump(s, open(sys.argv[1], "w"), indent=2)' "$out/summary.json" "${got[0]}" || exit 99
         [ "${got[0]}" = INT ] && exit 130; exit 143 ;;
      *) rm -f "$out/summary.json" "$out/stats.csv"; [ "${got[1]}" = INT ] && exit 130; exit 143 ;;
    esac ;;
  interrupted)
    /usr/bin/python3 -c 'import json, sys
s = json.load(open(sys.argv[1])); s["interrupted"] = {"by": "SIGTERM", "t": s["simulated_time_s"], "step": s["steps"]}
json.dump(s, open(sys.argv[1], "w"), indent=2)' "$out/summary.json" || exit 99
    exit 143 ;;
  *) echo "fake sph-run: unknown action '$action' in FAKE_RULES" >&2; exit 99 ;;
esac
exit 0
