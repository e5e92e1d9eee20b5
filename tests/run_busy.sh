#!/usr/bin/env bash
# The whole suite on a busy machine: two CPU burners run throughout, the suite runs RUNS times in
# a row (default 3). Fails if any run fails or if any process started by a run is still alive after
# it (found by a marker in the environment every child inherits).  Usage: tests/run_busy.sh [RUNS]
set -u
cd "$(dirname "$0")/.."
runs="${1:-3}"
python=.venv/bin/python
[ -x "$python" ] || { echo "no .venv: run 'make test' once first" >&2; exit 2; }
yes > /dev/null & burner1=$!
yes > /dev/null & burner2=$!
trap 'kill $burner1 $burner2 2>/dev/null' EXIT INT TERM
status=0
for i in $(seq 1 "$runs"); do
  marker="run-$$-$i-$RANDOM"
  start=$(date +%s)
  EXPLORER_TEST_RUN_ID="$marker" "$python" -m pytest -q -n auto -p no:cacheprovider > "/tmp/run_busy.$$.$i.log" 2>&1
  code=$?
  left=$(grep -l -s "EXPLORER_TEST_RUN_ID=$marker" /proc/[0-9]*/environ | cut -d/ -f3 | tr '\n' ' ')
  echo "run $i: exit $code in $(( $(date +%s) - start )) s: $(tail -n 1 "/tmp/run_busy.$$.$i.log")"
  if [ -n "$left" ]; then
    echo "run $i: processes left running: $left" >&2
    ps -o pid,ppid,etime,cmd -p ${left// /,} >&2 || true
    kill -9 $left 2>/dev/null
    status=1
  fi
  [ "$code" -eq 0 ] || { status=1; echo "log: /tmp/run_busy.$$.$i.log" >&2; }
done
exit $status
