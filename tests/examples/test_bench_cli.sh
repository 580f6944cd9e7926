#!/usr/bin/env bash
# flatsos_bench's command line (the benchmarks themselves are never run as a test): --help,
# a bad option exits 2 naming it, a model that cannot be loaded exits 1 naming the file.
bench=$1
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
expect 0 "--repetitions" -- "$bench" --help
expect 0 "--open-loop-only" -- "$bench" --help
expect 0 "--scaling-model" -- "$bench" --help
expect 0 "--ipopt-linear-solvers-only" -- "$bench" --help
expect 1 "$tmp/missing.json" -- "$bench" --scaling-only --scaling-model "$tmp/missing.json"
expect 2 "--repetitions" -- "$bench" --repetitions 0
expect 1 "$tmp/missing.json" -- "$bench" --model "$tmp/missing.json"
printf '{"bodies": []}' > "$tmp/bad.json"
expect 1 "bodies: must not be empty" -- "$bench" --model "$tmp/bad.json"
exit $fail
