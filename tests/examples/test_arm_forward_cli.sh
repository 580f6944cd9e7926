#!/usr/bin/env bash
# arm_forward: --help works, bad arguments exit 2 with a message, a good run writes states.sto,
# a bad model file exits non-zero naming the problem. Usage: test_arm_forward_cli.sh BIN SRC
set -u
bin=$1 src=$2
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
a0=0.135,0.040,0.404,0.556,0.414,0.068
expect 0 "The tendons' initial state is required" -- "$bin" --help
expect 2 "--q0-deg" -- "$bin" --q0-deg 1,2,3 --equilibrate-tendons --out "$tmp/o"
expect 2 "--a0" -- "$bin" --a0 0.1,0.2 --equilibrate-tendons --out "$tmp/o"
expect 2 "--duration-s" -- "$bin" --duration-s -1 --equilibrate-tendons --out "$tmp/o"
expect 2 "--accuracy" -- "$bin" --accuracy abc --equilibrate-tendons --out "$tmp/o"
expect 2 "--ls0-m" -- "$bin" --a0 $a0 --out "$tmp/o"
expect 2 "--integrator" -- "$bin" --integrator euler --equilibrate-tendons --out "$tmp/o"
expect 2 "--bogus" -- "$bin" --bogus
printf '{"bodies": []}' > "$tmp/bad.json"
expect 1 "bodies: must not be empty" -- "$bin" --model "$tmp/bad.json" --equilibrate-tendons --out "$tmp/o"
printf 'time,biceps\n0,0.5\n' > "$tmp/n.csv"
expect 1 "no column for muscle 'anterior_deltoid'" -- "$bin" --excitations "$tmp/n.csv" --equilibrate-tendons --out "$tmp/o"
expect 0 "wrote" -- "$bin" --q0-deg 0,10 --a0 $a0 --equilibrate-tendons --duration-s 0.05 --out "$tmp/good"
if ! grep -q "^endheader$" "$tmp/good/states.sto" || ! grep -q "/forceset/biceps/activation" "$tmp/good/states.sto"; then
  echo "FAILED: states.sto lacks the OpenSim header or columns"; fail=1
fi
# OpenSim's files: coordinates by path, controls apart; a Moco-style controls file drives a run.
grep -q "/jointset/shoulder/shoulder/value" "$tmp/good/states.sto" || { echo "FAILED: states.sto lacks coordinate paths"; fail=1; }
grep -q "excitation" "$tmp/good/states.sto" && { echo "FAILED: excitations in the states file"; fail=1; }
head -8 "$tmp/good/controls.sto" | grep -q "/forceset/biceps" || { echo "FAILED: controls.sto lacks /forceset/<muscle>"; fail=1; }
expect 0 "wrote" -- "$bin" --q0-deg 0,10 --a0 $a0 --equilibrate-tendons --duration-s 0.05 --excitations "$tmp/good/controls.sto" --out "$tmp/replay"
cmp -s <(tail -n +8 "$tmp/good/states.sto") <(tail -n +8 "$tmp/replay/states.sto") || { echo "FAILED: replaying controls.sto changed the motion"; fail=1; }
printf 'moco\nversion=1\nendheader\ntime\t/forceset/biceps\n0\t0.5\n' > "$tmp/short.sto"
expect 1 "no column for muscle 'anterior_deltoid'" -- "$bin" --excitations "$tmp/short.sto" --equilibrate-tendons --out "$tmp/o"
# Any model: a 1-joint elbow with the defaults sized from it.
models=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../models" && pwd)
expect 0 "final joint angles (deg): elbow=" -- "$bin" --model "$models/elbow_1dof.json" --equilibrate-tendons --duration-s 0.05 --out "$tmp/elbow"
# Units: a moment arm in centimetres is simulated, with a warning that names the field.
sed 's/"moment_arms_m": {"elbow": 0.03}}/"moment_arms_m": {"elbow": 3}}/' "$models/elbow_1dof.json" > "$tmp/cm.json"
expect 0 "arm_forward: warning: muscles[0] 'biceps'.moment_arms_m.elbow: 3 m is above 0.2 m" -- \
  "$bin" --model "$tmp/cm.json" --equilibrate-tendons --duration-s 0.01 --out "$tmp/cm"
exit $fail
