#!/usr/bin/env bash
# Installs the Debian packages flatsos needs, only those that are missing.
# Runs as root on a fresh Debian 12 (as CI does); uses sudo when not root.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libsimbody-dev libeigen3-dev coinor-libipopt-dev coinor-libclp-dev
  nlohmann-json3-dev libcli11-dev libboost-dev
  libgtest-dev libbenchmark-dev
  python3 python3-matplotlib python3-numpy
  python3-dev pybind11-dev python3-pybind11 python3-pytest
  python3-dask python3-distributed python3-pil
  python3-pip python3-venv python3-setuptools python3-wheel python3-build python3-jsonschema
)
if [[ "${FLATSOS_SANITIZE:-0}" == 1 ]]; then packages+=(clang libclang-rt-14-dev); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then exit 0; fi

echo "install_deps: installing ${missing[*]}"
sudo_cmd=()
if [[ $(id -u) != 0 ]]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
