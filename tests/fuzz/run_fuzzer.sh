#!/usr/bin/env bash
# Runs a libFuzzer target for a fixed number of inputs with a fixed seed. The run is repeatable
# for a given binary and seed corpus: -reload=0, and address-space randomization off (setarch -R;
# libFuzzer's comparison tables hash code addresses), when the system allows it. The seeds are
# copied into a fresh directory, so libFuzzer's new inputs never land in the source tree. Crash,
# leak and timeout inputs are kept in the working directory (crash-*, leak-*, timeout-*).
# -verbosity=0: no line per new input (thousands); reports and the final statistics still print.
# Usage: run_fuzzer.sh FUZZER RUNS SEED_FILE_OR_DIR... [-- LIBFUZZER_FLAGS...]
set -euo pipefail
fuzzer=$1 runs=$2; shift 2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/corpus"
while (($#)) && [[ $1 != -- ]]; do
  if [[ -d $1 ]]; then find "$1" -maxdepth 1 -type f -exec cp {} "$tmp/corpus/" \;; else cp "$1" "$tmp/corpus/"; fi
  shift
done
if (($#)); then shift; fi
no_aslr=()
if setarch "$(uname -m)" -R true 2>/dev/null; then no_aslr=(setarch "$(uname -m)" -R); fi
echo "run_fuzzer: $(ls "$tmp/corpus" | wc -l) seed inputs, $runs runs, -seed=1," \
  "${no_aslr[*]:-ASLR on (setarch -R not permitted): not repeatable}"
"${no_aslr[@]}" "$fuzzer" -seed=1 -runs="$runs" -reload=0 -timeout=60 -verbosity=0 \
  -print_final_stats=1 -artifact_prefix="$PWD/" "$@" "$tmp/corpus"
