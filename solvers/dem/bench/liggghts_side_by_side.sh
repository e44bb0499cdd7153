#!/usr/bin/env bash
# gonogo DEM engine against LIGGGHTS 3.8 on one core: same packing, contact law, box, skin and
# time step (gonogo-dem-bench --write-liggghts), N = 500, 5,000 and 50,000. Prints particle-steps
# per second of both codes, their ratio, and the memory per grain. Builds nothing.
#
#   [REPEATS=3] solvers/dem/bench/liggghts_side_by_side.sh BUILD/solvers/dem/gonogo-dem-bench [WORKDIR]
#   solvers/dem/bench/liggghts_side_by_side.sh --check BUILD/solvers/dem/gonogo-dem-bench [WORKDIR]
#
# Each code runs REPEATS times (default 1) per N, alternating, and the fastest run counts (the
# machine may be shared). --check runs N = 500 for 100 steps in both codes and prints kinetic energy and contact count
# every 10 steps, first for Hertz + damping only (no friction, no rolling resistance, no tangential
# dashpot), then for the full seed 000 law. See solvers/dem/README.md, "Benchmark".
#
# Needs the `liggghts` executable (Debian 12: apt-get install -y liggghts) and, for the LIGGGHTS
# memory figures, GNU time (apt-get install -y time). Not part of CI.
set -euo pipefail

check=0
repeats="${REPEATS:-1}"
if [[ "${1:-}" == "--check" ]]; then
  check=1
  shift
fi
if [[ $# -lt 1 || $# -gt 2 ]]; then
  echo "usage: $0 [--check] PATH/TO/gonogo-dem-bench [WORKDIR]" >&2
  exit 2
fi
bench="$(realpath "$1")"
work="${2:-$(mktemp -d /tmp/liggghts_side_by_side.XXXXXX)}"
mkdir -p "$work"
if [[ ! -x "$bench" ]]; then
  echo "not an executable: $bench (build it: ninja -C BUILD gonogo-dem-bench)" >&2
  exit 2
fi
if ! command -v liggghts >/dev/null 2>&1; then
  echo "liggghts not found. On Debian 12: apt-get install -y liggghts (LIGGGHTS-PUBLIC 3.8.0)" >&2
  exit 1
fi
gnu_time=""
if [[ -x /usr/bin/time ]] && /usr/bin/time -v true >/dev/null 2>&1; then
  gnu_time="/usr/bin/time -v"
fi

# One core, one thread, one MPI rank (no mpirun: LIGGGHTS starts as a singleton).
export OMP_NUM_THREADS=1
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

# LIGGGHTS thermo block (the lines between "Step ..." and "Loop time ...") as CSV.
liggghts_thermo_csv() {
  awk '/^ *Step /{on = 1; next} /^Loop time/{on = 0} on && $1 ~ /^[0-9]+$/ {
         line = $1; for (k = 2; k <= NF; ++k) line = line "," $k; print line }' "$1"
}

if [[ $check -eq 1 ]]; then
  for law in "hertz_damping_only:--friction 0 --rolling-limit 0 --tangential-damping 0" \
             "full_seed000_law:"; do
    name="${law%%:*}"
    flags="${law#*:}"
    dir="$work/check_$name"
    # shellcheck disable=SC2086
    "$bench" --grains 500 --steps 100 $flags --write-liggghts "$dir" --trace-every 10 >/dev/null
    (cd "$dir" && liggghts -in in.trace -log none >liggghts.out 2>&1)
    # shellcheck disable=SC2086
    "$bench" --grains 500 --steps 100 $flags --trace 10 >"$dir/gonogo.csv"
    liggghts_thermo_csv "$dir/liggghts.out" >"$dir/liggghts.csv"
    echo "== $name (N = 500; kinetic energy = translational + rotational, J)"
    # Columns: step, KE_t, KE_r, contacts, x y z vx vy vz of grain 1, the same of grain 251.
    paste -d, <(tail -n +2 "$dir/gonogo.csv") "$dir/liggghts.csv" | awk -F, '
      BEGIN { printf "%5s %14s %14s %10s %9s %9s %12s\n", "step", "KE gonogo", "KE LIGGGHTS",
              "rel diff", "contacts", "(LIGGGHTS)", "max |dx|/r" }
      { g = $2 + $3; l = $18 + $19; d = (l != 0) ? (g - l) / l : 0; if (d < 0) d = -d
        dx = 0; for (k = 5; k <= 7; ++k) { e = $k - $(k + 16); if (e < 0) e = -e; if (e > dx) dx = e }
        for (k = 11; k <= 13; ++k) { e = $k - $(k + 16); if (e < 0) e = -e; if (e > dx) dx = e }
        printf "%5d %14.6e %14.6e %10.2e %9d %9d %12.2e\n", $1, g, l, d, $4, $20, dx / 0.87e-3 }'
  done
  echo "(contacts of gonogo are counted at the first force evaluation: 0 at step 0)"
  echo "files in $work"
  exit 0
fi

# N, steps: 2e7 particle-steps each, a few seconds per code on one core.
cases=("500 40000" "5000 4000" "50000 400")
laws=("seed 000 law (LIGGGHTS: rolling_friction epsd3)|"
      "same law without rolling resistance (LIGGGHTS: rolling_friction off)|--rolling-limit 0")

declare -A gonogo_rss liggghts_rss
for law in "${laws[@]}"; do
  title="${law%%|*}"
  flags="${law#*|}"
  echo "== $title"
  printf "%7s %7s %10s %12s %10s %13s %13s %7s\n" N steps contacts "gonogo s" "LIGGGHTS s" \
    "gonogo p-s/s" "LIGGGHTS p-s/s" ratio
  for c in "${cases[@]}"; do
    read -r n steps <<<"$c"
    dir="$work/${flags:+norolling_}$n"
    # shellcheck disable=SC2086
    "$bench" --grains "$n" --steps "$steps" $flags --write-liggghts "$dir" >/dev/null
    g_wall=""
    l_wall=""
    for ((r = 0; r < repeats; ++r)); do
      # gonogo: grains,steps,threads,dt_s,contacts,rebuilds,wall_s,particle_steps_per_s,peak_rss_kib
      # shellcheck disable=SC2086
      g_line="$("$bench" --grains "$n" --steps "$steps" --threads 1 $flags | tail -1)"
      IFS=, read -r _ _ _ _ g_contacts _ wall _ g_rss <<<"$g_line"
      g_wall="$(awk -v a="$g_wall" -v b="$wall" 'BEGIN { print (a == "" || b < a) ? b : a }')"
      # LIGGGHTS: 10 warm-up steps, then the timed run; its last "Loop time" is the timing.
      (cd "$dir" && $gnu_time liggghts -in in.bench -log none >liggghts.out 2>liggghts.err) || {
        echo "liggghts failed; see $dir/liggghts.out and liggghts.err" >&2
        exit 1
      }
      wall="$(awk '/^Loop time of/{t = $4} END {print t}' "$dir/liggghts.out")"
      l_wall="$(awk -v a="$l_wall" -v b="$wall" 'BEGIN { print (a == "" || b < a) ? b : a }')"
      l_rss="$(awk -F: '/Maximum resident set size/{gsub(/ /, "", $2); print $2}' \
        "$dir/liggghts.err")"
    done
    if [[ -z "$flags" ]]; then
      gonogo_rss[$n]="$g_rss"
      liggghts_rss[$n]="${l_rss:-}"
    fi
    awk -v n="$n" -v s="$steps" -v c="$g_contacts" -v gw="$g_wall" -v lw="$l_wall" 'BEGIN {
      g = n * s / gw; l = n * s / lw
      printf "%7d %7d %10d %12.3f %10.3f %13.3e %13.3e %7.2f\n", n, s, c, gw, lw, g, l, g / l }'
  done
done

echo "== memory (peak resident set size, KiB; per grain from N = 5,000 to 50,000)"
awk -v g1="${gonogo_rss[5000]}" -v g2="${gonogo_rss[50000]}" -v g0="${gonogo_rss[500]}" \
    -v l1="${liggghts_rss[5000]:-}" -v l2="${liggghts_rss[50000]:-}" -v l0="${liggghts_rss[500]:-}" \
    'BEGIN {
      printf "gonogo:   %8d %8d %8d  -> %.0f bytes per grain\n", g0, g1, g2,
             (g2 - g1) * 1024 / 45000
      if (l2 != "") printf "LIGGGHTS: %8d %8d %8d  -> %.0f bytes per grain\n", l0, l1, l2,
             (l2 - l1) * 1024 / 45000
      else print "LIGGGHTS: no GNU time (apt-get install -y time)" }'
echo "files in $work"
