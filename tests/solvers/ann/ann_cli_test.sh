#!/bin/sh
# gonogo-ann at a tiny size: it writes the histories and the ensemble, prints the figure row of the
# architecture, and refuses malformed architectures by name before running any path; then fine-tunes
# that ensemble (--from) beside a new one from scratch and registers both (--register) with their
# provenance, the fine-tuned one naming its base. The first run records the RVE's fabric
# (--record-fabric): the exported columns carry it, of trace 1 at every step with contacts. A
# network carrying the coordination number (--carry) is trained; what cannot be carried is refused
# by name, as are --rig-weight and --rig-held-out-as without the rig's paths. With a rig run,
# --rig-held-out-as holds out the paths of another training count, none of them in training. The
# RVE's own spread (--packing-seeds): the study's packing (seed 1) against itself is 0 on every
# held-out path, another packing is not. The studies of the RVE alone: at rest (--rest-kpa) its
# stress is printed every tenth zero increment, and the increment-size study (--increment-kpa)
# prints p and q along each step count; an unknown --increment-path is refused by name.
set -eu
ann="$1"
out="$2"
rm -rf "$out"
mkdir -p "$out"
OMP_WAIT_POLICY=passive "$ann" --soil seed000_sand_rve100 --preset ci --steps 5 --walks 2 \
  --architecture 8 --epochs 2 --threads 1 --record-fabric --out "$out" > "$out/figures.csv" \
  2> "$out/progress.txt"
grep -q '^mlp-8-tanh-anchored,3,2,[0-9][0-9]*,' "$out/figures.csv"
test -s "$out/training.npy"
test -s "$out/held_out.npy.columns.txt"
/usr/bin/python3 - "$out" <<'PYTHON'
import sys
import numpy as np
out = sys.argv[1]
columns = open(f'{out}/training.npy.columns.txt').read().split()
table = np.load(f'{out}/training.npy')
assert table.shape[1] == len(columns), (table.shape, columns)
trace = table[:, [columns.index(f'fabric_{c}') for c in ('xx', 'yy', 'zz')]].sum(axis=1)
coordination = table[:, columns.index('coordination_number')]
assert ((coordination >= 0) & (coordination < 12)).all(), 'a coordination number out of range'
assert (coordination > 0).any(), 'no step with contacts'
assert np.abs(trace - (coordination > 0)).max() < 1e-12, 'the fabric is not of trace 1'
PYTHON
for k in 0 1 2; do test -s "$out/mlp-8-tanh-anchored/member_$k.pt"; done
test -s "$out/mlp-8-tanh-anchored/envelope.bin"
for bad in 8xq 64a gruq; do
  if "$ann" --architecture "$bad" > /dev/null 2> "$out/error.txt"; then
    echo "--architecture $bad was accepted" >&2
    exit 1
  fi
  grep -q -- "--architecture: '$bad'" "$out/error.txt"
done
OMP_WAIT_POLICY=passive "$ann" --soil seed000_sand_rve100 --preset ci --steps 5 --walks 1 \
  --architecture 8 --epochs 2 --threads 1 --from "$out/mlp-8-tanh-anchored" \
  --register "$out/data" > "$out/tuned.csv" 2> "$out/tuned_progress.txt"
grep -q '^mlp-8-tanh-anchored-from-mlp-8-tanh-anchored,3,2,[0-9][0-9]*,' "$out/tuned.csv"
grep -q '^mlp-8-tanh-anchored,3,2,[0-9][0-9]*,' "$out/tuned.csv"
test "$(grep -c '^# registered model seed000_sand_rve100-' "$out/tuned.csv")" = 2
grep -q '^from_model = mlp-8-tanh-anchored$' "$out"/data/models/*-from-*/model.txt
grep -q '^fe_de_preset = ci$' "$out"/data/models/seed000_sand_rve100-mlp-8-tanh-anchored-1/model.txt
if "$ann" --from "$out/no-such-model" > /dev/null 2> "$out/error.txt"; then
  echo "--from a missing model was accepted" >&2
  exit 1
fi
grep -q "model" "$out/error.txt"
# A network that carries the RVE's coordination number (--carry), and what cannot be carried,
# refused by name before any path runs.
OMP_WAIT_POLICY=passive "$ann" --soil seed000_sand_rve100 --preset ci --steps 5 --walks 1 \
  --architecture 8 --epochs 2 --threads 1 --carry coordination_number > "$out/carrying.csv" \
  2> "$out/carrying_progress.txt"
grep -q '^mlp-8-tanh-anchored-carrying-coordination_number,3,2,[0-9][0-9]*,' "$out/carrying.csv"
for bad in void_ratio fabric_xz; do
  if "$ann" --carry "$bad" > /dev/null 2> "$out/error.txt"; then
    echo "--carry $bad was accepted" >&2
    exit 1
  fi
  grep -q -- "--carry.*'$bad'" "$out/error.txt"
done
if "$ann" --rig-weight 4 > /dev/null 2> "$out/error.txt"; then
  echo "--rig-weight without the rig's paths was accepted" >&2
  exit 1
fi
grep -q -- "--rig-weight: weighs the rig's recorded paths: give --rig-load-n too" "$out/error.txt"
if "$ann" --rig-held-out-as 4 > /dev/null 2> "$out/error.txt"; then
  echo "--rig-held-out-as without the rig's paths was accepted" >&2
  exit 1
fi
grep -q -- "--rig-held-out-as: chooses among the rig's recorded paths: give --rig-load-n too" \
  "$out/error.txt"
# Eight of the rig's recorded paths in training, held out those of four (--rig-held-out-as):
# the points four training points hold out, none of them in training.
OMP_WAIT_POLICY=passive "$ann" --soil seed000_sand_rve100 --preset tiny --steps 5 --walks 0 \
  --architecture 8 --epochs 1 --threads 1 --rig-load-n 1000 --rig-points 8 --rig-held-out-as 4 \
  > "$out/rig.csv" 2> "$out/rig_progress.txt"
/usr/bin/python3 - "$out/rig.csv" <<'PYTHON'
import re, sys
line = next(l for l in open(sys.argv[1]) if l.startswith('# rig run at 1000 N'))
found = re.search(r"(\d+) points' paths recorded, 8 in training, 2 held out "
                  r"\(the points' indices: training ([\d ]+), held out ([\d ]+)\)", line)
assert found, line
paths = int(found.group(1))
training = [int(k) for k in found.group(2).split()]
held_out = [int(k) for k in found.group(3).split()]
# As --rig-points 4 holds out (EvenlySpread from RigHeldOutOffset): from paths / 8 + 1, every
# paths / 2.
assert held_out == [int(paths // 8 + 1 + k * paths / 2) % paths for k in range(2)], line
assert len(set(training)) == 8 and not set(training) & set(held_out), line
PYTHON
if "$ann" --carry coordination_number --architecture gru8 > /dev/null 2> "$out/error.txt"; then
  echo "--carry with a GRU was accepted" >&2
  exit 1
fi
grep -q -- "--carry: a GRU carries its hidden state" "$out/error.txt"
OMP_WAIT_POLICY=passive "$ann" --soil seed000_sand_rve100 --preset ci --steps 5 --walks 0 \
  --architecture 8 --epochs 1 --threads 1 --packing-seeds 1 2 > "$out/spread.csv" \
  2> "$out/spread_progress.txt"
grep -q '^packing_seed,triaxial.*,generation_s$' "$out/spread.csv"
/usr/bin/python3 - "$out/spread.csv" <<'PYTHON'
import sys
rows = {line.split(',')[0]: [float(x) for x in line.strip().split(',')[1:-1]]
        for line in open(sys.argv[1]) if line[:2] in ('1,', '2,')}
assert len(rows['1']) == 7 and all(x == 0 for x in rows['1']), rows
assert len(rows['2']) == 7 and all(x > 0 for x in rows['2']), rows
PYTHON
if "$ann" --packing-seeds 0 > /dev/null 2> "$out/error.txt"; then
  echo "--packing-seeds 0 was accepted" >&2
  exit 1
fi
grep -q -- "--packing-seeds" "$out/error.txt"
OMP_WAIT_POLICY=passive "$ann" --soil seed000_sand_rve100 --preset ci --rest-kpa 5 \
  --rest-steps 20 --rest-axial-strain 0.005 > "$out/rest.csv"
OMP_WAIT_POLICY=passive "$ann" --soil seed000_sand_rve100 --preset ci --increment-kpa 10 \
  --increment-steps 8 > "$out/increment.csv"
/usr/bin/python3 - "$out/rest.csv" "$out/increment.csv" <<'PYTHON'
import sys
rest = [line.strip().split(',') for line in open(sys.argv[1]) if not line.startswith('#')]
assert rest[0] == ['step', 'p_pa', 'q_pa', 'p_change_pct', 'q_change_pct'], rest[0]
assert [row[0] for row in rest[1:]] == ['0', '10', '20'], rest
for step, p, q, p_change, q_change in rest[1:]:
    # Compressed oedometrically by 0.5 % from 5 kPa: p and q of tens of kPa, held within 1 %.
    assert 20e3 < float(p) < 200e3 and 10e3 < float(q) < 300e3, (p, q)
    assert abs(float(p_change)) < 1 and abs(float(q_change)) < 1, (p_change, q_change)
increment = [line.strip().split(',') for line in open(sys.argv[2]) if not line.startswith('#')]
assert increment[0] == ['steps', 'fraction', 'strain', 'p_pa', 'q_pa', 'seconds'], increment[0]
assert len(increment) > 2 and all(row[0] == '8' for row in increment[1:]), increment
# Sheared from 10 kPa, the packing's deviator rises above the isotropic start's.
assert max(float(row[4]) for row in increment[1:]) > 10e3, increment
PYTHON
if "$ann" --increment-kpa 10 --increment-path bogus > /dev/null 2> "$out/error.txt"; then
  echo "--increment-path bogus was accepted" >&2
  exit 1
fi
grep -q -- "--increment-path: unknown path 'bogus'" "$out/error.txt"
echo "ann_cli_test: ok"
