#!/usr/bin/env bash
# Fuzzes the three parsers that read untrusted bytes, each for a bounded time, with libFuzzer:
#   gonogo-fuzz-map_request   the request messages (SubmitMap's first message, a curve query)
#   gonogo-fuzz-vehicle_json  vehicle and soil-table JSON files
#   gonogo-fuzz-terrain       uploaded rasters (GDAL from memory, geo::LoadTerrain)
#
#   deploy/fuzz.sh [--seconds S] [TARGET...]     (default 60 s each, every target)
#
# Builds them with clang into ./build-fuzz (GONOGO_FUZZ_BUILD_DIR), instrumented with coverage,
# AddressSanitizer and UBSan. Each run starts from its seed corpus (tests/fuzz/corpus/TARGET) and
# first replays every kept regression input (tests/fuzz/regressions/TARGET). A crash, leak, hang or
# sanitizer report fails the script and leaves the input in build-fuzz/findings/TARGET: copy it into
# tests/fuzz/regressions/TARGET with the fix, so that it is replayed from then on.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${GONOGO_FUZZ_BUILD_DIR:-$root/build-fuzz}
seconds=60
targets=()
while [ $# -gt 0 ]; do
  case $1 in
    --seconds) seconds=$2; shift 2 ;;
    -*) echo "usage: deploy/fuzz.sh [--seconds S] [map_request|vehicle_json|terrain ...]" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
[ ${#targets[@]} -gt 0 ] || targets=(map_request vehicle_json terrain)

if [ ! -f "$build/build.ninja" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGONOGO_FUZZ=ON \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ >/dev/null
fi
ninja -C "$build" -j "${GONOGO_BUILD_JOBS:-$(nproc)}" "${targets[@]/#/gonogo-fuzz-}"

# A smaller quarantine than ASan's 256 MB default: GDAL's allocations churn, and the RSS limit below
# is for what the parsers keep, not for what ASan holds back.
export ASAN_OPTIONS=${ASAN_OPTIONS:-quarantine_size_mb=32}
status=0
for target in "${targets[@]}"; do
  binary=$build/tests/fuzz/gonogo-fuzz-$target
  corpus=$build/corpus/$target  # grows across runs; the seeds stay as committed
  findings=$build/findings/$target
  mkdir -p "$corpus" "$findings"
  regressions=("$root/tests/fuzz/regressions/$target"/*)
  if [ -e "${regressions[0]}" ]; then
    echo "== $target: replaying ${#regressions[@]} kept regression inputs"
    "$binary" -rss_limit_mb=2048 -timeout=20 "${regressions[@]}" || { echo "== $target: a kept regression fails again"; status=1; }
  fi
  echo "== $target: fuzzing for $seconds s"
  if ! "$binary" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=20 -print_final_stats=1 \
      -artifact_prefix="$findings/" "$corpus" "$root/tests/fuzz/corpus/$target" 2>"$build/$target.log"; then
    tail -40 "$build/$target.log"
    echo "== $target: FOUND a failure; its input is in $findings"
    status=1
  else
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb|cov:" "$build/$target.log" | tail -3
  fi
done
exit $status
