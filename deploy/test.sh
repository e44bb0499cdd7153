#!/usr/bin/env bash
# Installs the dependencies, builds, and runs the whole test suite (what CI runs).
# Extra arguments go to ctest, e.g. `deploy/test.sh -LE slow` for the quick loop.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${GONOGO_BUILD_DIR:-$root/build}
"$root/deploy/install-deps.sh"
"$root/deploy/build.sh"
# mpirun as root (CI, containers) and more ranks than cores.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
cd "$build"
ctest --output-on-failure --timeout 900 "$@"
