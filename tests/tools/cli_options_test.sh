#!/usr/bin/env bash
# The command-line programs parse their options with CLI11: --help prints the help and exits 0,
# and an unknown or mistyped option is an error (non-zero exit) whose message names the option.
#
#   cli_options_test.sh NAME=PATH...   (tests/tools/CMakeLists.txt passes every program)
#
# For each program: --help; --no-such-option; a near miss of one of its real options (below).
# Nothing here runs a simulation: every call stops in the parser, so the test takes about a second.
set -u

# A mistyped option per program: one letter off a real one, given a value, as a user would type it.
declare -A near_miss=(
  [gonogo-rig]="drawbar --soil lll_dry_sand --wheel-diameter 1 --wheel-width 0.3 --wheel-lod 1000"
  [gonogo-dem-bench]="--grain 500"
  [gonogo-rve]="triaxial --axial-strian 0.1"
  [gonogo-rve-bench]="--rve 4"
  [geo_bench]="--size 100"
  [gonogo-bench-map]="--sizes 100"
  [gonogo-bench-bekker]="--second 1"
  [gonogo-crosscheck-tiers]="--cone_index lll_dry_sand=500000"
  [gonogo-fe-de]="--wheel-diameter 0.5 --wheel-width 0.2 --wheel-lod 1000"
  [gonogo-bench-fe-ann]="--fe-de-curv fe_de.csv"
)
# The option each near miss above must name in its message.
declare -A near_miss_option=(
  [gonogo-rig]="--wheel-lod" [gonogo-dem-bench]="--grain" [gonogo-rve]="--axial-strian"
  [gonogo-rve-bench]="--rve" [geo_bench]="--size" [gonogo-bench-map]="--sizes"
  [gonogo-bench-bekker]="--second" [gonogo-crosscheck-tiers]="--cone_index"
  [gonogo-fe-de]="--wheel-lod" [gonogo-bench-fe-ann]="--fe-de-curv"
)

failures=0
fail() {
  echo "FAIL: $*"
  failures=$((failures + 1))
}

# expect_error NAME OPTION PATH ARGS...: non-zero exit, and OPTION in the output.
expect_error() {
  local name="$1" option="$2" path="$3"
  shift 3
  local out rc
  out="$(timeout 30 "$path" "$@" 2>&1)"
  rc=$?
  if [[ $rc -eq 0 ]]; then
    fail "$name $*: exit 0, expected an error"
  elif [[ $rc -eq 124 ]]; then
    fail "$name $*: still running after 30 s (the parser did not stop it)"
  elif [[ "$out" != *"$option"* ]]; then
    fail "$name $*: exit $rc, but the message does not name $option: $out"
  else
    echo "ok: $name $* -> exit $rc: ${out%%$'\n'*}"
  fi
}

# expect_help NAME PATH ARGS...: exit 0 and a usage line on stdout.
expect_help() {
  local name="$1" path="$2"
  shift 2
  local out rc
  out="$(timeout 30 "$path" "$@" 2>/dev/null)"
  rc=$?
  if [[ $rc -ne 0 ]]; then
    fail "$name $*: exit $rc, expected 0"
  elif [[ "$out" != *"Usage: $name"* ]]; then
    fail "$name $*: no 'Usage: $name' line in the help: $out"
  else
    echo "ok: $name $* -> exit 0"
  fi
}

[[ $# -eq ${#near_miss[@]} ]] || fail "expected ${#near_miss[@]} programs, got $#"
for arg in "$@"; do
  name="${arg%%=*}"
  path="${arg#*=}"
  if [[ ! -x "$path" ]]; then
    fail "$name: not an executable: $path (build it first)"
    continue
  fi
  if [[ -z "${near_miss[$name]+set}" ]]; then
    fail "$name: no near miss listed in $0"
    continue
  fi
  expect_help "$name" "$path" --help
  expect_error "$name" --no-such-option "$path" --no-such-option
  # shellcheck disable=SC2086
  expect_error "$name" "${near_miss_option[$name]}" "$path" ${near_miss[$name]}
done

# gonogo-rig's options belong to its commands: help per command, and errors inside a command.
for arg in "$@"; do
  [[ "${arg%%=*}" == gonogo-rig ]] || continue
  rig="${arg#*=}"
  for command in drawbar constant-slip towed bevameter; do
    expect_help "gonogo-rig $command" "$rig" "$command" --help
    expect_error "gonogo-rig $command" --no-such-option "$rig" "$command" --soil lll_dry_sand \
      --no-such-option
  done
  expect_error gonogo-rig frobnicate "$rig" frobnicate
  expect_error gonogo-rig --wheel-load "$rig" bevameter --soil lll_dry_sand --wheel-load 1000
done

if [[ $failures -ne 0 ]]; then
  echo "$failures failure(s)"
  exit 1
fi
echo "all passed"
