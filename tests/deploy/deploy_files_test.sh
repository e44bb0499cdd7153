#!/usr/bin/env bash
# The deployment files that cannot run here are checked with the tools that can:
# - deploy/systemd/gonogo.service with systemd-analyze verify (the unit with ExecStart pointed at
#   this build, since the unit names /opt/gonogo), and the same unit pointed at a missing binary
#   must fail verification (the check can fail);
# - every deploy shell script with bash -n;
# - the container recipes: each names Debian 12, installs with deploy/install-deps.sh and builds with
#   deploy/build.sh (there is no container runtime here to build them).
#   deploy_files_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
source_dir=$1
build_dir=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

if command -v systemd-analyze > /dev/null; then
  sed "s|/opt/gonogo/build|$build_dir|g" "$source_dir/deploy/systemd/gonogo.service" > "$work/gonogo.service"
  systemd-analyze verify "$work/gonogo.service"
  sed "s|/opt/gonogo/build|$work/missing|g" "$source_dir/deploy/systemd/gonogo.service" > "$work/broken.service"
  if systemd-analyze verify "$work/broken.service" 2> /dev/null; then
    echo "FAIL: systemd-analyze verify accepted a unit whose binary is missing" >&2
    exit 1
  fi
  echo "deploy_files_test: gonogo.service verifies"
else
  echo "deploy_files_test: no systemd-analyze; the unit is not checked"
fi
for script in "$source_dir"/deploy/*.sh "$source_dir"/deploy/gonogo-supervise "$source_dir"/deploy/slurm/*; do
  bash -n "$script"
done
for recipe in "$source_dir/deploy/container/Dockerfile" "$source_dir/deploy/container/gonogo.def"; do
  grep -q "debian:12" "$recipe" && grep -q "deploy/install-deps.sh" "$recipe" && grep -q "deploy/build.sh" "$recipe" ||
    { echo "FAIL: $recipe does not build from Debian 12 with the project's scripts" >&2; exit 1; }
done
echo "deploy_files_test: PASS"
