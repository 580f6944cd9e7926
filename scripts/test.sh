#!/usr/bin/env bash
# The test command: installs what is missing, builds, runs every test through ctest.
# Exit code = result.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/scripts/install_deps.sh"
"$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure --timeout 1200 -j "$(nproc)"
