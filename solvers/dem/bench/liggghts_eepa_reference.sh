#!/usr/bin/env bash
# Force-overlap curves of the Edinburgh elasto-plastic adhesion model as LIGGGHTS 3.8 codes it
# (`pair_style gran model edinburgh`, LIGGGHTS-PUBLIC src/normal_model_edinburgh.h, contributed
# from the University of Edinburgh), for the EEPA reference test of the engine
# (tests/solvers/dem/eepa_test.cc, EepaNormal.MatchesTheLiggghtsEdinburghModel).
#
#   solvers/dem/bench/liggghts_eepa_reference.sh [OUT.csv]
#
# Two 10 mm grains of seed 001's FGS (G 5e8 Pa, nu 0.25, f0 -2 N, lambda_p 0.9, n 1.5) at rest;
# grain 2 is moved by displace_atoms and the force re-evaluated (`run 0`) at each overlap. Three
# cases: the surface energy and tensile exponent of Table 3 (7 J/m^2, chi 1.5) and a strong one
# (5000 J/m^2, chi 2), each loaded to 6e-5 m, unloaded to 3e-5 m, reloaded to 1e-4 m and unloaded
# to 1e-6 m; and one whose pull is capped (5e5 J/m^2, chi 1.5), loaded to 1e-4 m and unloaded to
# 1e-6 m (no reload: from its adhesive branch LIGGGHTS takes the adhesion of the reloaded line,
# the engine that of d_max; see solvers/dem/README.md). Writes case,overlap_m,force_n (default:
# tests/solvers/dem/data/liggghts_edinburgh.csv). Needs `liggghts` (Debian 12: apt-get install -y
# liggghts); not part of CI, whose test reads the committed CSV.
set -euo pipefail
out="${1:-$(dirname "$0")/../../../tests/solvers/dem/data/liggghts_edinburgh.csv}"
if ! command -v liggghts >/dev/null 2>&1; then
  echo "liggghts not found. On Debian 12: apt-get install -y liggghts (LIGGGHTS-PUBLIC 3.8.0)" >&2
  exit 1
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work="$(mktemp -d /tmp/liggghts_eepa.XXXXXX)"
cat >"$work/in.edinburgh" <<'LIGGGHTS'
units si
atom_style sphere
atom_modify map array
boundary f f f
newton off
communicate single vel yes
region box block -0.05 0.05 -0.05 0.05 -0.05 0.05 units box
create_box 1 box
hard_particles yes
neighbor 0.002 bin
neigh_modify delay 0
# seed 001 Table 3, FGS: E = 2 G (1 + nu) = 1.25e9 Pa; k2 / k1 = 1 / (1 - lambda_p) = 10.
fix m1 all property/global youngsModulus peratomtype 1.25e9
fix m2 all property/global poissonsRatio peratomtype 0.25
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.6
fix m4 all property/global coefficientFriction peratomtypepair 1 0.5
fix m5 all property/global UnloadingStiffness peratomtypepair 1 10.0
fix m6 all property/global pullOffForce peratomtypepair 1 -2.0
fix m7 all property/global surfaceEnergy peratomtypepair 1 ${surface_energy}
fix m8 all property/global adhesionExponent scalar ${tensile_exponent}
fix m9 all property/global overlapExponent scalar 1.5
fix m10 all property/global coefficientAdhesionStiffness peratomtypepair 1 0.0
pair_style gran model edinburgh tangential history
pair_coeff * *
create_atoms 1 single 0.0 0.0 0.0 units box
create_atoms 1 single 0.01 0.0 0.0 units box
set atom * diameter 0.01 density 2500
group moving id 2
variable force equal fx[2]
variable overlap equal 0.01-(x[2]-x[1])
thermo_style custom step
thermo 1000000
# Moves of grain 2 along x (m) and how many of each (-var schedule: the case's).
include schedule.${schedule}
label leg
variable i loop ${count}
label step
displace_atoms moving move ${move} 0 0 units box
run 0 post no
print "ROW,${overlap},${force}"
next i
jump SELF step
next move
next count
jump SELF leg
LIGGGHTS
# Load to 6e-5 m, unload to 3e-5 m, reload to 1e-4 m, unload to 1e-6 m; or straight to 1e-4 m
# and back.
printf 'variable move index -2e-6 2e-6 -2e-6 1e-6\nvariable count index 30 15 35 99\n' \
  >"$work/schedule.cycle"
printf 'variable move index -2e-6 1e-6\nvariable count index 50 99\n' >"$work/schedule.once"
echo "case,overlap_m,force_n" >"$out"
for case in "table3 7.0 1.5 cycle" "strong 5000.0 2.0 cycle" "capped 5.0e5 1.5 once"; do
  read -r name surface_energy tensile_exponent schedule <<<"$case"
  (cd "$work" && liggghts -in in.edinburgh -log none -var surface_energy "$surface_energy" \
    -var tensile_exponent "$tensile_exponent" -var schedule "$schedule" >"$name.out" 2>&1) || {
    echo "liggghts failed; see $work/$name.out" >&2
    exit 1
  }
  grep '^ROW,' "$work/$name.out" | sed "s/^ROW/$name/" >>"$out"
done
echo "wrote $(($(wc -l <"$out") - 1)) rows to $out (LIGGGHTS output in $work)"
