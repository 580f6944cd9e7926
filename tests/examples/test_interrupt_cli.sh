#!/usr/bin/env bash
# arm_receding_horizon stopped by SIGTERM halfway through a long run: it exits 143 (128 + the
# signal) after writing complete files of what it simulated, and its summary says it was
# interrupted, when and why. Its rows are streamed: the run keeps no table. Usage: RH
set -u
rh=$1
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
out="$tmp/long"
"$rh" --duration-s 600 --no-predictions --out "$out" >"$tmp/stdout" 2>"$tmp/stderr" &
pid=$!
# Wait until the run is under way (its streamed rows appear), then stop it.
for _ in $(seq 100); do
  compgen -G "$out/simulation.sto.rows.tmp*" >/dev/null && break
  sleep 0.1
done
sleep 1
kill -TERM "$pid"
wait "$pid"
rc=$?
[[ $rc -eq 143 ]] || { echo "FAILED: exit code $rc after SIGTERM, expected 143"; cat "$tmp/stderr"; fail=1; }
grep -q "interrupted by SIGTERM" "$tmp/stderr" || { echo "FAILED: stderr does not say SIGTERM stopped the run"; fail=1; }
summary="$out/summary.json"
grep -q '"interrupted": true' "$summary" || { echo "FAILED: the summary does not say the run was interrupted"; fail=1; }
grep -q '"success": false' "$summary" || { echo "FAILED: an interrupted run reported success"; fail=1; }
grep -q 'interrupted=true' "$out/simulation.sto" || { echo "FAILED: the table does not say it was interrupted"; fail=1; }
# Complete files: the header's row count is the rows there are, every row has every column, and
# both tables end at the same time, where the run stopped (before its 600 s).
for f in simulation.sto simulation_controls.sto; do
  awk -F'\t' '/^nRows=/ {split($0, a, "="); n = a[2]} /^nColumns=/ {split($0, a, "="); c = a[2]}
              body && NF != c {bad = 1} body {rows++; last = $1} /^time/ {body = 1}
              END {exit !(rows == n && !bad && rows > 100 && last < 600)}' "$out/$f" ||
    { echo "FAILED: $f is not a complete table of the run so far"; fail=1; }
done
ls "$out" | grep -q tmp && { echo "FAILED: temporary files left in $out"; ls "$out"; fail=1; }
last_state=$(tail -1 "$out/simulation.sto" | cut -f1)
last_control=$(tail -1 "$out/simulation_controls.sto" | cut -f1)
[[ "$last_state" == "$last_control" ]] || { echo "FAILED: the tables end at $last_state and $last_control"; fail=1; }
exit $fail
