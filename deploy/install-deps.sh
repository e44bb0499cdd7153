#!/usr/bin/env bash
# Installs everything gonogo needs to build, run and test on Debian 12, from Debian's archive only.
# Idempotent: packages already present are left alone, and apt is not touched when nothing is missing.
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git
  # numerics and parallelism
  libeigen3-dev libopenmpi-dev openmpi-bin
  # service
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc grpc-proto
  # storage, rasters, JSON
  libsqlite3-dev sqlite3 libgdal-dev gdal-bin python3-gdal nlohmann-json3-dev
  # command-line parsing for every program; structured logging in the server
  libcli11-dev libspdlog-dev
  # neural networks of the fe-ann tier (the PyTorch 1.13 C++ API), and Python's torch that loads
  # its saved models
  libtorch-dev python3-torch
  # drawing the PNG plots and quicklooks (server/geo), and their font
  libcairo2-dev fonts-dejavu-core
  # tests; the products opened in QGIS (offscreen) and the STAC item checked against its schema;
  # certificates for the TLS tests
  libgtest-dev libgmock-dev python3-qgis python3-jsonschema openssl
  # fuzzing the parsers of untrusted bytes: clang with libFuzzer and the sanitizers (deploy/fuzz.sh)
  clang libclang-rt-dev
  # deployment under Slurm, tested with real daemons on one machine (deploy/slurm), and the Python
  # client (clients/python): Debian's gRPC and protobuf for Python, pytest, matplotlib for its plots,
  # pandas for its DataFrames
  slurmctld slurmd slurm-client munge
  python3-grpcio python3-protobuf python3-pytest python3-matplotlib python3-numpy python3-pandas
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
