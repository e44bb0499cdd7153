#!/bin/sh
# gonogo-ann at a tiny size: it writes the histories and the ensemble, prints the figure row of
# the architecture, and refuses malformed architectures by name before running any path; then
# fine-tunes that ensemble (--from) beside a new one from scratch and registers both (--register)
# with their provenance, the fine-tuned one naming its base. The first run records the RVE's
# fabric (--record-fabric): the exported columns carry it, of trace 1 at every step with contacts.
# A network carrying the coordination number (--carry) is trained; what cannot be carried is
# refused by name. The RVE's own spread (--packing-seeds): the study's packing (seed 1) against
# itself is 0 on every held-out path, another packing is not.
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
echo "ann_cli_test: ok"
