#!/usr/bin/env bash
# Drained triaxial compression of the seed 000 RVE in LIGGGHTS 3.8, the peer run of
# `gonogo-rve triaxial` (solvers/dem/rve/README.md, "Triaxial against LIGGGHTS").
#
#   solvers/dem/bench/liggghts_rve_triaxial.sh [--seeds N] [--summary FILE] [OUT_DIR]
#
# For seeds 1..N (default 4), one LIGGGHTS run each, one MPI rank, no mpirun:
#   1. a random gas of 500 grains, radii uniform in 0.87 mm (1 +- 0.2), density 2650 kg/m^3,
#      at solid fraction 0.25 in a fully periodic cube (placed as Rve::Generate places them:
#      largest first, at random, without overlap; Python's Mersenne Twister, seeded with the seed);
#   2. isotropic consolidation to 100 kPa without friction (rolling resistance on, as in the
#      engine), each normal stress servo-held by `fix deform ... variable` (remap x), until the
#      mean stress is within 1 %, every normal stress within 3 % of 100 kPa and the
#      unbalanced-force ratio below 5e-3, checked every 100 steps (the engine's criteria but for
#      the shear stresses, which an orthogonal cell cannot servo; see the input);
#   3. friction restored (mu 0.452) and drained triaxial compression: constant true axial strain
#      rate along z, `fix deform z trate`, at the engine's rate (inertial number 1e-3 at the mean
#      stress after consolidation: 3.5 /s), lateral stresses servo-held at 100 kPa, to 10 % axial
#      strain in 100 rows.
# The contact law is the engine's seed 000 law as LIGGGHTS writes it: `gran model hertz
# tangential history rolling_friction epsd3`, E 1.5 GPa, nu 0.293, restitution 0.5 (Tsuji
# dashpot, tangential dashpot on, limitForce off), mu 0.452, rolling friction eta 0.99, rolling
# stiffness 3.375 = 1.5 beta (epsd3 scales the secant k_n = 4/3 E* sqrt(r_e d); the engine scales
# the tangent 2 E* sqrt(r_e d)), no rolling dashpot. Time step 0.3 of the Rayleigh step of the
# smallest grain, skin 0.2 r_max, neighbour check every step: all as in the engine.
#
# Stress: `compute pressure ... virial` (pair virial only, no kinetic part, as the engine),
# compression positive. Strains: axial -ln(l_z / l_z0), volumetric -ln(V / V0), the integrals of
# the rates the engine sums.
#
# Writes OUT_DIR/seed_S/triaxial.csv (axial_strain,volumetric_strain,p_pa,q_pa,sigma_xx_pa,
# sigma_yy_pa,sigma_zz_pa; row 0 is the consolidated state) and the summary (default
# OUT_DIR/summary.csv; --summary FILE elsewhere): per seed the largest q/p up to 10 % axial
# strain, the axial strain there, the largest dilation (-volumetric strain), the friction angle
# of that q/p (sin phi = 3 M / (6 + M)), the solid fraction and coordination number after
# consolidation, and the wall time. solvers/dem/bench/gonogo_rve_triaxial_seeds.sh writes the
# same summary for the engine. Needs `liggghts` (Debian 12: apt-get install -y liggghts) and
# python3; not part of CI, whose test reads the committed summary
# (tests/solvers/dem/data/liggghts_rve_triaxial.csv).
set -euo pipefail

seeds=4
summary=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seeds) seeds="$2"; shift 2 ;;
    --summary) summary="$2"; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    -*) echo "unknown option $1" >&2; exit 2 ;;
    *) break ;;
  esac
done
if [[ $# -gt 1 ]] || ! [[ "$seeds" =~ ^[1-9][0-9]*$ ]]; then
  echo "usage: $0 [--seeds N >= 1] [--summary FILE] [OUT_DIR]" >&2
  exit 2
fi
out="${1:-/tmp/liggghts_rve_triaxial}"
summary="${summary:-$out/summary.csv}"
for tool in liggghts python3; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "$tool not found (Debian 12: apt-get install -y liggghts python3)" >&2
    exit 1
  fi
done
mkdir -p "$out"
export OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

# The random gas as a LIGGGHTS data file; prints r_min_m and the grains' solid volume (m^3).
cat >"$out/random_gas.py" <<'PYTHON'
import math, random, sys
seed, path = int(sys.argv[1]), sys.argv[2]
grains, mean_radius_m, radius_spread, solid_fraction, density_kg_m3 = 500, 0.87e-3, 0.2, 0.25, 2650.0
rng = random.Random(seed)
radii_m = sorted((mean_radius_m * (1 + radius_spread * (2 * rng.random() - 1)) for _ in range(grains)),
                 reverse=True)
solid_m3 = sum(4 / 3 * math.pi * r**3 for r in radii_m)
side_m = (solid_m3 / solid_fraction) ** (1 / 3)
placed = []
for r in radii_m:
    for attempt in range(100000):
        centre = [side_m * rng.random() for _ in range(3)]
        if all(sum((c - q - side_m * round((c - q) / side_m)) ** 2 for c, q in zip(centre, other))
               > (r + r_other) ** 2 for other, r_other in placed):
            placed.append((centre, r))
            break
    else:
        sys.exit("random placement failed")
with open(path, "w") as data:
    data.write("random gas, seed %d\n\n%d atoms\n1 atom types\n\n" % (seed, grains))
    for axis in "xyz":
        data.write("0 %.17g %slo %shi\n" % (side_m, axis, axis))
    data.write("\nAtoms\n\n")
    for k, (c, r) in enumerate(placed):
        data.write("%d 1 %.17g %g %.17g %.17g %.17g\n" % (k + 1, 2 * r, density_kg_m3, *c))
print("%.17g %.17g" % (min(radii_m), solid_m3))
PYTHON

cat >"$out/in.rve_triaxial" <<'LIGGGHTS'
# Seed 000 RVE: consolidation and drained triaxial (solvers/dem/bench/liggghts_rve_triaxial.sh).
# -var r_min_m: the smallest radius of data.gas.
variable youngs_pa equal 1.5e9
variable poisson equal 0.293
variable density_kg_m3 equal 2650
variable mean_radius_m equal 0.87e-3
variable confining_pa equal 1e5
variable max_inertial_number equal 1e-3
variable final_axial_strain equal 0.1
variable rows equal 100
variable shear_modulus_pa equal ${youngs_pa}/(2*(1+${poisson}))
# Rayleigh step of the smallest grain (Li, Xu & Thornton 2005), times the engine's 0.3.
variable dt_s equal 0.3*PI*${r_min_m}*sqrt(${density_kg_m3}/${shear_modulus_pa})/(0.1631*${poisson}+0.8766)
variable skin_m equal 0.2*1.2*${mean_radius_m}

atom_style sphere
atom_modify map array
boundary p p p
# LIGGGHTS refuses shear history with newton on.
newton off
communicate single vel yes
units si
# Its sanity check stops at E > 1 GPa otherwise.
hard_particles yes
read_data data.gas
neighbor ${skin_m} bin
neigh_modify delay 0 every 1 check yes
fix m1 all property/global youngsModulus peratomtype ${youngs_pa}
fix m2 all property/global poissonsRatio peratomtype ${poisson}
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.5
# Frictionless consolidation; the loading friction is set before the triaxial run (the
# property registry is rebuilt at every run's init).
fix m4 all property/global coefficientFriction peratomtypepair 1 0.0
fix m5 all property/global coefficientRollingFriction peratomtypepair 1 0.99
fix m6 all property/global coefficientRollingViscousDamping peratomtypepair 1 0.0
# epsd3: k_r = rollingStiffness k_n rmu^2 r_e^2 with the secant k_n = 4/3 E* sqrt(r_e d); the
# engine: beta k_n eta^2 r_e^2 with the tangent k_n = 2 E* sqrt(r_e d); so 1.5 beta = 3.375.
fix m7 all property/global rollingStiffness scalar 3.375
pair_style gran model hertz tangential history rolling_friction epsd3
pair_coeff * *
timestep ${dt_s}
fix integrate all nve/sphere

# Stress from the pair virial alone (compression positive), evaluated every step because the
# servo reads it every step (fix deform does not schedule it on the first step).
compute stress_pa all pressure thermo_temp virial
fix stress_every_step all ave/time 1 1 1 c_stress_pa mode vector
compute contacts_atom all contact/atom
compute contacts_sum all reduce sum c_contacts_atom
variable contacts equal c_contacts_sum/2
variable net_force_n atom sqrt(fx*fx+fy*fy+fz*fz)
compute mean_net_force_n all reduce ave v_net_force_n
variable p_pa equal (c_stress_pa[1]+c_stress_pa[2]+c_stress_pa[3])/3
variable q_pa equal sqrt(0.5*((c_stress_pa[1]-c_stress_pa[2])^2+(c_stress_pa[2]-c_stress_pa[3])^2+(c_stress_pa[3]-c_stress_pa[1])^2)+3*(c_stress_pa[4]^2+c_stress_pa[5]^2+c_stress_pa[6]^2))
# Unbalanced-force ratio, mean net force over mean contact force. Without friction every contact
# force is along its branch, so tr(virial) = sum |d| |f| = 3 p V; with |d| ~ 2 r_mean the mean
# contact force is 3 p V / (2 r_mean contacts).
variable unbalanced equal c_mean_net_force_n*v_contacts*2*${mean_radius_m}/(3*v_p_pa*vol+1e-300)

# The engine's rate cap: inertial number I = rate d sqrt(rho / p) at most 1e-3 at the mean stress
# (at least the confining one), times 10 while the packing is a gas (fewer contacts than grains),
# times 3 otherwise.
variable p_for_rate_pa equal (v_p_pa>${confining_pa})*v_p_pa+(v_p_pa<=${confining_pa})*${confining_pa}
variable inertial_rate_1_s equal ${max_inertial_number}/(2*${mean_radius_m}*sqrt(${density_kg_m3}/v_p_for_rate_pa))
variable rate_cap_1_s equal v_inertial_rate_1_s*(3+7*(v_contacts<atoms))
# Servo: each step closes 1/servo_steps of the stress gap of an axis judged with a fixed
# stiffness (the engine judges it with its affine tangent): rate = (sigma - target) / (D n dt).
variable servo_stiffness_pa equal 3e7
variable servo_steps equal 15
variable raw_rate_x equal (c_stress_pa[1]-${confining_pa})/(v_servo_stiffness_pa*v_servo_steps*dt)
variable raw_rate_y equal (c_stress_pa[2]-${confining_pa})/(v_servo_stiffness_pa*v_servo_steps*dt)
variable raw_rate_z equal (c_stress_pa[3]-${confining_pa})/(v_servo_stiffness_pa*v_servo_steps*dt)
variable rate_x equal (v_raw_rate_x>v_rate_cap_1_s)*v_rate_cap_1_s-(v_raw_rate_x<-v_rate_cap_1_s)*v_rate_cap_1_s+(abs(v_raw_rate_x)<=v_rate_cap_1_s)*v_raw_rate_x
variable rate_y equal (v_raw_rate_y>v_rate_cap_1_s)*v_rate_cap_1_s-(v_raw_rate_y<-v_rate_cap_1_s)*v_rate_cap_1_s+(abs(v_raw_rate_y)<=v_rate_cap_1_s)*v_raw_rate_y
variable rate_z equal (v_raw_rate_z>v_rate_cap_1_s)*v_rate_cap_1_s-(v_raw_rate_z<-v_rate_cap_1_s)*v_rate_cap_1_s+(abs(v_raw_rate_z)<=v_rate_cap_1_s)*v_raw_rate_z
# fix deform "variable" sets the length to (length at the run's init) + the first variable; the
# length at init is the one below (later chunks run with "pre no", which keeps that init), so
# each step moves the current length by rate * length * dt.
variable lx0_m equal $(lx)
variable ly0_m equal $(ly)
variable lz0_m equal $(lz)
variable dlx_m equal lx-v_lx0_m+v_rate_x*lx*dt
variable dly_m equal ly-v_ly0_m+v_rate_y*ly*dt
variable dlz_m equal lz-v_lz0_m+v_rate_z*lz*dt
variable vlx_m_s equal v_rate_x*lx
variable vly_m_s equal v_rate_y*ly
variable vlz_m_s equal v_rate_z*lz
# Frictionless, the grains may be remapped affinely (remap x): the contact velocities then lack
# the affine part, which only the normal dashpot would see here (no friction, no tangential
# spring; the rolling springs see spins only, and a stretch has none).
fix consolidate all deform 1 x variable v_dlx_m v_vlx_m_s y variable v_dly_m v_vly_m_s z variable v_dlz_m v_vlz_m_s remap x

# Settled as the engine settles (mean stress within 1 %, each normal stress within 3 % of the
# target, unbalanced-force ratio below 5e-3), except that the shear stresses are left out: the
# engine holds them at 0 by shearing its cell, but in a triclinic periodic box this LIGGGHTS
# build made no ghost atoms (no periodic images) and then lost atoms, so the cell stays
# orthogonal and a jammed packing keeps the shear stress it jammed with (printed with
# CONSOLIDATED).
thermo_style custom step v_p_pa c_stress_pa[1] c_stress_pa[2] c_stress_pa[3] c_stress_pa[4] c_stress_pa[5] c_stress_pa[6] v_contacts v_unbalanced vol
thermo_modify norm no lost error
thermo 100
variable settled equal "abs(v_p_pa-v_confining_pa)<0.01*v_confining_pa && abs(c_stress_pa[1]-v_confining_pa)<0.03*v_confining_pa && abs(c_stress_pa[2]-v_confining_pa)<0.03*v_confining_pa && abs(c_stress_pa[3]-v_confining_pa)<0.03*v_confining_pa && v_unbalanced<5e-3"
variable consolidation_chunks loop 4000
run 100
label consolidation
if "${settled} > 0" then "jump SELF consolidated"
run 100 pre no post no
next consolidation_chunks
jump SELF consolidation
print "CONSOLIDATION_FAILED within 400,000 steps"
quit
label consolidated
print "CONSOLIDATED steps $(step) p_pa $(v_p_pa) q_pa $(v_q_pa) sigma_xx_pa $(c_stress_pa[1]) sigma_yy_pa $(c_stress_pa[2]) sigma_zz_pa $(c_stress_pa[3]) volume_m3 $(vol) contacts $(v_contacts) sigma_xy_pa $(c_stress_pa[4]) sigma_xz_pa $(c_stress_pa[5]) sigma_yz_pa $(c_stress_pa[6])"

# Drained triaxial compression.
unfix consolidate
fix m4 all property/global coefficientFriction peratomtypepair 1 0.452
variable axial_rate_1_s equal $(v_inertial_rate_1_s)
variable total_steps equal ceil(${final_axial_strain}/(${axial_rate_1_s}*dt))
variable steps_per_row equal floor(${total_steps}/${rows})
# Steps counted from the start of loading, so that the rows fall on multiples of steps_per_row;
# the every-step stress fix is re-made so that it schedules the virial from step 0 again.
unfix stress_every_step
reset_timestep 0
fix stress_every_step all ave/time 1 1 1 c_stress_pa mode vector
# The grains get the streaming velocity of the axial compression, and the cell moves with
# remap v: positions are not remapped, a grain crossing a face and every periodic image take the
# cell's rate, so every contact sees the affine part of its relative velocity, as in the engine.
# With remap x the tangential springs and the dashpots would see only the grains' velocities
# relative to the affine field (the rolling springs see spins only, and a stretch has none).
velocity all ramp vz $(v_axial_rate_1_s*0.5*lz) $(-v_axial_rate_1_s*0.5*lz) z $(zlo) $(zhi) sum yes units box
# Lateral servo, gentler than the consolidation's: with remap v a change of the cell's rate
# reaches the grains as a wave from the faces, and 5x this gain rang at a 6-step period.
variable servo_stiffness_pa equal 5e7
variable servo_steps equal 5
variable rate_cap_1_s equal 3*v_inertial_rate_1_s
variable lx0_m equal $(lx)
variable ly0_m equal $(ly)
variable lz0_m equal $(lz)
fix triaxial all deform 1 x variable v_dlx_m v_vlx_m_s y variable v_dly_m v_vly_m_s z trate -${axial_rate_1_s} remap v
variable axial_strain equal -ln(lz/v_lz0_m)
variable volumetric_strain equal -ln(vol/(v_lx0_m*v_ly0_m*v_lz0_m))
fix rows all print ${steps_per_row} "ROW,$(v_axial_strain),$(v_volumetric_strain),$(v_p_pa),$(v_q_pa),$(c_stress_pa[1]),$(c_stress_pa[2]),$(c_stress_pa[3])" screen yes
thermo 1000
print "TRIAXIAL axial_rate_1_s ${axial_rate_1_s} total_steps ${total_steps} steps_per_row ${steps_per_row} dt_s $(dt)"
run ${total_steps}
# The last row, at the final strain (the script drops it when the last chunk printed it).
print "ROW,$(v_axial_strain),$(v_volumetric_strain),$(v_p_pa),$(v_q_pa),$(c_stress_pa[1]),$(c_stress_pa[2]),$(c_stress_pa[3])"
LIGGGHTS

printf "seed,peak_q_over_p,axial_strain_at_peak,largest_dilation,peak_friction_deg,initial_solid_fraction,initial_coordination_number,wall_s\n" >"$summary.part"
for ((seed = 1; seed <= seeds; ++seed)); do
  dir="$out/seed_$seed"
  mkdir -p "$dir"
  read -r r_min_m solid_m3 < <(python3 "$out/random_gas.py" "$seed" "$dir/data.gas")
  start_s=$(date +%s.%N)
  (cd "$dir" && liggghts -in ../in.rve_triaxial -var r_min_m "$r_min_m" -log none >liggghts.out 2>&1) || {
    echo "liggghts failed for seed $seed; see $dir/liggghts.out" >&2
    exit 1
  }
  wall_s=$(awk -v a="$start_s" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  if ! grep -q '^CONSOLIDATED' "$dir/liggghts.out"; then
    echo "seed $seed: consolidation did not settle; see $dir/liggghts.out" >&2
    exit 1
  fi
  # Row 0 (the consolidated state), then the rows of fix print ("ROW,..." on the screen).
  awk '/^CONSOLIDATED/ { printf "0,0,%.6e,%.6e,%.6e,%.6e,%.6e\n", $5, $7, $9, $11, $13 }
       /^ROW,/ { split($0, f, ","); if (f[2] == last) next; last = f[2]
                 printf "%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e\n", f[2], f[3], f[4], f[5], f[6], f[7], f[8] }' \
    "$dir/liggghts.out" |
    sed '1i axial_strain,volumetric_strain,p_pa,q_pa,sigma_xx_pa,sigma_yy_pa,sigma_zz_pa' \
      >"$dir/triaxial.csv"
  consolidated=$(grep '^CONSOLIDATED' "$dir/liggghts.out")
  awk -F, -v seed="$seed" -v wall="$wall_s" -v solid="$solid_m3" -v line="$consolidated" '
    BEGIN { split(line, f, " "); volume = f[15]; contacts = f[17] }
    NR > 2 { ratio = $4 / $3
             if (ratio > peak) { peak = ratio; at = $1 }
             if (-$2 > dilation) dilation = -$2 }
    END { s = 3 * peak / (6 + peak)
          printf "%d,%.6f,%.6f,%.6f,%.3f,%.5f,%.4f,%s\n", seed, peak, at, dilation,
                 atan2(s, sqrt(1 - s * s)) * 45 / atan2(1, 1), solid / volume,
                 2 * contacts / 500, wall }' "$dir/triaxial.csv" >>"$summary.part"
  tail -1 "$summary.part"
done
mv "$summary.part" "$summary"
echo "summary: $summary; per seed: $out/seed_*/triaxial.csv"
