#!/usr/bin/env bash
# Drained triaxial compression of the seed 000 RVE with the engine, seeds 1..N: the engine's side
# of solvers/dem/bench/liggghts_rve_triaxial.sh (solvers/dem/rve/README.md, "Triaxial against
# LIGGGHTS"), in the same summary format.
#
#   solvers/dem/bench/gonogo_rve_triaxial_seeds.sh [--seeds N] [--summary FILE]
#       [--gonogo-rve PATH] [OUT_DIR]
#
# Runs `gonogo-rve triaxial --seed S --axial-strain 0.1 --rows 100` for S = 1..N (default 4): 500
# grains, a random gas at solid fraction 0.25 consolidated isotropically and frictionless to
# 100 kPa, then drained triaxial compression at the quasi-static rate (inertial number 1e-3),
# lateral stresses held at 100 kPa, to 10 % axial strain. Writes OUT_DIR/seed_S/gonogo-rve.csv
# (the driver's full CSV), OUT_DIR/seed_S/triaxial.csv (axial_strain,volumetric_strain,p_pa,
# q_pa,sigma_xx_pa,sigma_yy_pa,sigma_zz_pa) and the summary (default OUT_DIR/summary.csv): per
# seed the largest q/p up to 10 % axial strain, the axial strain there, the largest dilation
# (-volumetric strain), the friction angle of that q/p (sin phi = 3 M / (6 + M)), the solid
# fraction and coordination number after consolidation, and the wall time. Builds nothing
# (`gonogo-rve` defaults to build/solvers/dem/rve/gonogo-rve under the repository root).
set -euo pipefail

seeds=4
summary=""
binary="$(dirname "$0")/../../../build/solvers/dem/rve/gonogo-rve"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seeds) seeds="$2"; shift 2 ;;
    --summary) summary="$2"; shift 2 ;;
    --gonogo-rve) binary="$2"; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    -*) echo "unknown option $1" >&2; exit 2 ;;
    *) break ;;
  esac
done
if [[ $# -gt 1 ]] || ! [[ "$seeds" =~ ^[1-9][0-9]*$ ]]; then
  echo "usage: $0 [--seeds N >= 1] [--summary FILE] [--gonogo-rve PATH] [OUT_DIR]" >&2
  exit 2
fi
if [[ ! -x "$binary" ]]; then
  echo "not an executable: $binary (build it: ninja -C BUILD gonogo-rve)" >&2
  exit 2
fi
out="${1:-/tmp/gonogo_rve_triaxial}"
summary="${summary:-$out/summary.csv}"
mkdir -p "$out"

printf "seed,peak_q_over_p,axial_strain_at_peak,largest_dilation,peak_friction_deg,initial_solid_fraction,initial_coordination_number,wall_s\n" >"$summary.part"
for ((seed = 1; seed <= seeds; ++seed)); do
  dir="$out/seed_$seed"
  mkdir -p "$dir"
  start_s=$(date +%s.%N)
  "$binary" triaxial --seed "$seed" --axial-strain 0.1 --rows 100 --threads 1 \
    >"$dir/gonogo-rve.csv" 2>"$dir/gonogo-rve.err" || {
    echo "gonogo-rve failed for seed $seed; see $dir/gonogo-rve.err" >&2
    exit 1
  }
  wall_s=$(awk -v a="$start_s" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  # Driver columns: step,time_s,axial_strain,volumetric_strain,shear_strain,p_pa,q_pa,
  # sigma_xx_pa,sigma_yy_pa,sigma_zz_pa,...,solid_fraction (15),coordination_number (16),...
  awk -F, 'BEGIN { print "axial_strain,volumetric_strain,p_pa,q_pa,sigma_xx_pa,sigma_yy_pa,sigma_zz_pa" }
           NR > 1 { printf "%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e\n", $3 + 0, $4 + 0, $6, $7, $8, $9, $10 }' \
    "$dir/gonogo-rve.csv" >"$dir/triaxial.csv"
  read -r solid_fraction coordination < <(awk -F, 'NR == 2 { print $15, $16 }' "$dir/gonogo-rve.csv")
  awk -F, -v seed="$seed" -v wall="$wall_s" -v solid="$solid_fraction" -v z="$coordination" '
    NR > 2 { ratio = $4 / $3
             if (ratio > peak) { peak = ratio; at = $1 }
             if (-$2 > dilation) dilation = -$2 }
    END { s = 3 * peak / (6 + peak)
          printf "%d,%.6f,%.6f,%.6f,%.3f,%.5f,%.4f,%s\n", seed, peak, at, dilation,
                 atan2(s, sqrt(1 - s * s)) * 45 / atan2(1, 1), solid, z, wall }' \
    "$dir/triaxial.csv" >>"$summary.part"
  tail -1 "$summary.part"
done
mv "$summary.part" "$summary"
echo "summary: $summary; per seed: $out/seed_*/triaxial.csv"
