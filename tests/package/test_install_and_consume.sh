#!/usr/bin/env bash
# Installs flatsos from the build tree into a temporary prefix, then configures, builds and runs
# a separate project that uses find_package(flatsos) in a plain Release build (CMake's -DNDEBUG
# included) with `using namespace SimTK;` in its files. Then checks that the two ways client code
# breaks stop at flatsos' guards with their explanation: `using namespace SimTK;` before a header
# that includes Eigen, and NDEBUG without the package's -UNDEBUG. Finally runs the installed
# programs from a moved copy of the prefix, elsewhere: they find their models there.
# With a Python interpreter given, the installed Python package is imported from the prefix.
# Usage: BUILD_DIR SOURCE_DIR [PYTHON]
set -euo pipefail
build=$1 src=$2 python=${3:-}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" >/dev/null
cmake -S "$src/tests/package/consumer" -B "$tmp/consumer" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$tmp/consumer" >/dev/null
"$tmp/consumer/consumer"

fail=0
# The wrong include order fails, and the first error is the guard's.
if out=$(cmake --build "$tmp/consumer" --target wrong_order 2>&1); then
  echo "FAILED: 'using namespace SimTK;' before an Eigen header compiled"; fail=1
elif [[ $(grep -m1 "error" <<<"$out") != *simtk_namespace_guard.hpp* ]]; then
  echo "FAILED: the first error is not flatsos' guard:"; grep -m3 "error" <<<"$out"; fail=1
fi
# A build outside CMake that keeps NDEBUG stops at the guard (it would crash at run time).
printf '#include "flatsos/plugin/force/hill_muscle.hpp"\nint main() { return 0; }\n' > "$tmp/ndebug.cpp"
if out=$(c++ -std=c++17 -DNDEBUG -I"$tmp/prefix/include" -I/usr/include/simbody -fsyntax-only "$tmp/ndebug.cpp" 2>&1); then
  echo "FAILED: code with NDEBUG compiled against flatsos' Simbody headers"; fail=1
elif ! grep -q "ndebug_guard.hpp" <<<"$out"; then
  echo "FAILED: the NDEBUG error does not point to flatsos' guard:"; grep -m3 "error" <<<"$out"; fail=1
fi
c++ -std=c++17 -DNDEBUG -UNDEBUG -I"$tmp/prefix/include" -I/usr/include/simbody -fsyntax-only "$tmp/ndebug.cpp" ||
  { echo "FAILED: -UNDEBUG after -DNDEBUG does not compile"; fail=1; }

# The installed programs and models, relocated: libraries, headers, package, programs, models.
for f in bin/flatsos bin/arm_forward bin/arm_open_loop bin/arm_receding_horizon bin/flatsos_bench \
         share/flatsos/models/arm_richter_warner.json share/flatsos/models/elbow_1dof.json \
         include/flatsos/plugin/force/hill_muscle.hpp; do
  [[ -e "$tmp/prefix/$f" ]] || { echo "FAILED: $f not installed"; fail=1; }
done
ls "$tmp"/prefix/lib*/cmake/flatsos/flatsosConfig.cmake >/dev/null || { echo "FAILED: no CMake package"; fail=1; }
if [[ -n $python ]]; then
  site=$(ls -d "$tmp"/prefix/lib*/python3*/dist-packages 2>/dev/null | head -1)
  if [[ -z $site ]]; then
    echo "FAILED: the Python package is not installed"; fail=1
  elif ! (cd "$tmp" && PYTHONPATH=$site "$python" -c "
import flatsos
arm = flatsos.Model('$tmp/prefix/share/flatsos/models/arm_richter_warner.json')
plan = flatsos.plan_open_loop(arm, [0, 0.2], [0, 0], None, [1.5, 0], 3.0, 10.0)
assert flatsos.__file__.startswith('$site'), flatsos.__file__
assert plan.status == 'solved', plan.message"); then
    echo "FAILED: the installed Python package does not plan"; fail=1
  fi
fi
mv "$tmp/prefix" "$tmp/moved"
mkdir "$tmp/work" && cd "$tmp/work"
if ! "$tmp/moved/bin/arm_open_loop" --out ol >/dev/null 2>&1; then
  echo "FAILED: the installed arm_open_loop does not run from a moved prefix"; fail=1
elif ! grep -q "\"model_file\": \"$tmp/moved/share/flatsos/models/arm_richter_warner.json\"" ol/summary.json; then
  echo "FAILED: the installed program did not use the installed model:"; grep model_file ol/summary.json; fail=1
fi
"$tmp/moved/bin/arm_receding_horizon" --model "$tmp/moved/share/flatsos/models/elbow_1dof.json" --out rh >/dev/null 2>&1 ||
  { echo "FAILED: the installed arm_receding_horizon does not run"; fail=1; }
# One command: flatsos <subcommand> runs the installed programs and the installed Python package.
"$tmp/moved/bin/flatsos" plan --model "$tmp/moved/share/flatsos/models/elbow_1dof.json" --out plan >/dev/null 2>&1 &&
  grep -q '"status": "solved"' plan/summary.json || { echo "FAILED: the installed 'flatsos plan' does not plan"; fail=1; }
if [[ -n $python ]]; then
  "$tmp/moved/bin/flatsos" animate --model "$tmp/moved/share/flatsos/models/elbow_1dof.json" \
    --states plan/simulation.sto --out plan/motion.gif >/dev/null 2>&1 && [[ -s plan/motion.gif ]] ||
    { echo "FAILED: the installed 'flatsos animate' does not find the installed Python package"; fail=1; }
  "$tmp/moved/bin/flatsos" plot plan >/dev/null 2>&1 && [[ -s plan/open_loop_activations.png ]] ||
    { echo "FAILED: the installed 'flatsos plot' does not draw"; fail=1; }
fi
exit $fail
