#!/usr/bin/env bash
# Configures and builds gonogo into ./build (override with GONOGO_BUILD_DIR). Safe to re-run.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${GONOGO_BUILD_DIR:-$root/build}
jobs=${GONOGO_BUILD_JOBS:-$(nproc)}
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
ninja -C "$build" -j "$jobs"
