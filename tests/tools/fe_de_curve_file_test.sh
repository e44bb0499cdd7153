#!/usr/bin/env bash
# A long fe-de curve kept across runs: gonogo-fe-de --checkpoint-dir stopped part way and run
# again resumes from its checkpoint and answers the curve of an uninterrupted run, byte for byte
# (and its --samples-csv records too, whose first lines checkpoint_records.py reads from the
# checkpoint); --curve-csv keeps it with its configuration, and gonogo-bench-fe-ann --fe-de-curve
# compares an fe-ann curve with it, refusing a file of another rig or a damaged one by name before
# it trains.
#
#   fe_de_curve_file_test.sh GONOGO_FE_DE GONOGO_BENCH_FE_ANN
#
# On the tiny configuration (128 RVEs of 100 grains, 900 FE steps): three fe-de runs and one
# bench run, about two minutes on 2 cores.
set -u
fe_de="$1"
bench="$2"
export OMP_WAIT_POLICY=passive
work="$(mktemp -d)"
trap 'kill $pid 2>/dev/null; rm -rf "$work"' EXIT
pid=""
failures=0
fail() {
  echo "FAIL: $*"
  failures=$((failures + 1))
}

rig=(--preset tiny --soil seed000_sand_rve100 --wheel-diameter 0.5 --wheel-width 0.2
     --wheel-load 1000 --slip-step 0.25 --threads 2)
kept=(--checkpoint-dir "$work/checkpoint" --checkpoint-every-s 1 --curve-csv "$work/curve.csv"
      --samples-csv "$work/samples.csv")

# 1. Started, stopped once a checkpoint exists and a few more seconds have passed.
"$fe_de" "${rig[@]}" "${kept[@]}" > "$work/first.out" 2> "$work/first.err" &
pid=$!
for _ in $(seq 1 240); do
  [[ -f "$work/checkpoint/rig.state" ]] && break
  sleep 0.5
done
sleep 3
kill -TERM "$pid" 2>/dev/null
wait "$pid" 2>/dev/null
pid=""
[[ -f "$work/checkpoint/rig.state" ]] || fail "no checkpoint (rig.state) after 120 s"
[[ -f "$work/curve.csv" ]] && fail "the stopped run wrote its curve file"

# 2. The same command again: it resumes (its first progress is past 0 %) and keeps the curve.
"$fe_de" "${rig[@]}" "${kept[@]}" > "$work/resumed.out" 2> "$work/resumed.err" ||
  fail "the resumed run failed: $(tail -c 400 "$work/resumed.err")"
first_progress="$(tr '\r' '\n' < "$work/resumed.err" | grep -m1 -oE '^ *[0-9.]+ %' | tr -d ' %')"
if [[ -z "$first_progress" ]] || awk -v p="$first_progress" 'BEGIN { exit !(p <= 0) }'; then
  fail "the second run did not resume: its first progress is '${first_progress}' %"
else
  echo "ok: resumed at ${first_progress} %"
fi
grep -q "the checkpoint in $work/checkpoint is kept" "$work/resumed.err" ||
  fail "the resumed run does not say where its checkpoint is kept"

# 3. An uninterrupted run answers the same curve, and the same records as the resumed run (whose
#    records before its checkpoint came back from it).
"$fe_de" "${rig[@]}" --samples-csv "$work/straight_samples.csv" > "$work/straight.out" \
  2> "$work/straight.err" ||
  fail "the uninterrupted run failed: $(tail -c 400 "$work/straight.err")"
if cmp -s "$work/straight.out" "$work/resumed.out" && [[ -s "$work/straight.out" ]]; then
  echo "ok: the resumed curve equals the uninterrupted one"
else
  fail "the resumed curve differs from the uninterrupted one:"
  diff "$work/straight.out" "$work/resumed.out"
fi

if cmp -s "$work/straight_samples.csv" "$work/samples.csv"; then
  echo "ok: the resumed run's records equal the uninterrupted one's"
else
  fail "the resumed run's records differ from the uninterrupted one's"
fi
# A checkpoint's records so far (solvers/rig/studies/checkpoint_records.py, reading rig.state as
# the rig writes it) are the first lines of the run's own records file.
checkpoint_records="$(dirname "$0")/../../solvers/rig/studies/checkpoint_records.py"
python3 "$checkpoint_records" "$work/checkpoint/rig.state" > "$work/checkpoint_records.csv" ||
  fail "checkpoint_records.py could not read the kept checkpoint"
lines="$(wc -l < "$work/checkpoint_records.csv")"
if [[ "$lines" -ge 2 ]] &&
   head -n "$lines" "$work/samples.csv" | cmp -s - "$work/checkpoint_records.csv"; then
  echo "ok: the checkpoint's $((lines - 1)) records are the run's first"
else
  fail "the checkpoint's records ($lines lines) are not the first lines of the run's records"
fi
# The records: a header, then one line every 5 ms over the 0.45 s procedure, the ramp (phase 4)
# last (that they filter to the curve's bits is FeDeTier's test).
records="$(awk -F, 'NR == 1 && $1 == "time_s" && $6 == "drawbar_pull_n" && $9 == "sinkage_m" { h = 1 }
  NR > 1 { n++; last = $2 } END { if (h) print n, last }' "$work/samples.csv")"
read -r record_count last_phase <<< "$records"
if [[ -z "$records" || "$record_count" -lt 88 || "$last_phase" != 4 ]]; then
  fail "the records file: '$records' (records, last phase) or no header: $(head -2 "$work/samples.csv")"
else
  echo "ok: $record_count records, the last of phase $last_phase"
fi

# 4. The kept file: its configuration line, then the same CSV.
head -1 "$work/curve.csv" > "$work/head.txt"
for word in "tier=fe-de-1-tiny" "soil=seed000_sand_rve100" "preset=tiny" "overrides=none" \
            "wheel_diameter_m=0.5" "wheel_load_n=1000" "elements=128" "fe_steps=900"; do
  grep -q -- "$word" "$work/head.txt" ||
    fail "the curve file's first line lacks $word: $(cat "$work/head.txt")"
done
tail -n +2 "$work/curve.csv" | cmp -s - "$work/straight.out" ||
  fail "the curve file's CSV differs from the printed curve"
# It and the records are the user's files, as any other they write (not a checkpoint's owner-only
# mode), and no temporary file is left beside them.
expected_mode=$(printf '%o' $((0666 & ~$(umask))))
for file in "$work/curve.csv" "$work/samples.csv"; do
  mode=$(stat -c %a "$file")
  [ "$mode" = "$expected_mode" ] || fail "$file has mode $mode, not $expected_mode (umask $(umask))"
  [ ! -e "$file.tmp" ] || fail "$file.tmp was left behind"
done

# 5. The bench refuses a file of another rig, or a damaged one, naming the field, before training.
expect_refusal() {
  local reason="$1" expected="$2"
  shift 2
  local out rc
  out="$(timeout 60 "$bench" "$@" 2>&1)"
  rc=$?
  if [[ $rc -ne 1 ]]; then
    fail "$reason: exit $rc, expected 1: $out"
  elif [[ "$out" != *"--fe-de-curve"* || "$out" != *"$expected"* ]]; then
    fail "$reason: the message does not name --fe-de-curve and '$expected': $out"
  elif [[ "$out" == *"training:"* ]]; then
    fail "$reason: refused only after training"
  else
    echo "ok: $reason -> ${out##*gonogo-bench-fe-ann: }"
  fi
}
expect_refusal "another wheel load" "wheel_load_n=1000" --fe-de-curve "$work/curve.csv" \
  --wheel-load-n 1500
expect_refusal "another preset" "preset=tiny" --fe-de-curve "$work/curve.csv" --preset ci
expect_refusal "no such file" "cannot read" --fe-de-curve "$work/none.csv"
tail -n +2 "$work/curve.csv" > "$work/no_configuration.csv"
expect_refusal "no configuration line" "line 1" --fe-de-curve "$work/no_configuration.csv"
sed '/^0.5000,/s/^0.5000,[^,]*/0.5000,abc/' "$work/curve.csv" > "$work/damaged.csv"
expect_refusal "a damaged row" "line 5: 'abc'" --fe-de-curve "$work/damaged.csv"
sed '/^0.5000,/d' "$work/curve.csv" > "$work/three_slips.csv"
expect_refusal "other slips" "slips are" --fe-de-curve "$work/three_slips.csv"

# 5b. The bench refuses a recipe its options make wrong, naming the option, before training.
for args in "--pressures-kpa 5 2.5|--pressures-kpa: must be in increasing order" \
            "--pressures-kpa 5|--pressures-kpa: must hold 2 to 64 pressures" \
            "--walk-share 0.6 --rotated-copies 1|--walk-share: weighs the walks"; do
  out="$(timeout 60 "$bench" --no-fe-de ${args%%|*} 2>&1)"
  rc=$?
  if [[ $rc -ne 1 || "$out" != *"${args##*|}"* || "$out" == *"training:"* ]]; then
    fail "the bench with ${args%%|*}: exit $rc, expected 1 and '${args##*|}' before training: $out"
  else
    echo "ok: the bench with ${args%%|*} -> ${out##*gonogo-bench-fe-ann: }"
  fi
done

# 6. gonogo-fe-de refuses options that would be ignored: a checkpoint period without a directory,
#    a curve file or checkpoints for a run that is not one whole curve.
for args in "--checkpoint-every-s 5|--checkpoint-dir" "--curve-csv x.csv --bevameter|--bevameter" \
            "--checkpoint-dir ck --stop-after-s 60|--stop-after-s"; do
  out="$(timeout 30 "$fe_de" "${rig[@]}" ${args%%|*} 2>&1)"
  rc=$?
  if [[ $rc -eq 0 || "$out" != *"${args##*|}"* ]]; then
    fail "gonogo-fe-de ${args%%|*}: exit $rc, expected an error naming ${args##*|}: $out"
  else
    echo "ok: gonogo-fe-de ${args%%|*} -> exit $rc: ${out%%$'\n'*}"
  fi
done

# 7. The bench compares a tiny model's fe-ann curve with a right file; the model is of the recipe
#    its options ask for (pressure-scaled at 3 kPa; three training pressures, so its held-out
#    triaxial lies between the first two).
out="$(timeout 600 "$bench" --fe-de-curve "$work/curve.csv" --walks 2 --epochs 5 --threads 2 \
  --samples-csv "$work/ann_samples.csv" --pressure-scaled 3000 --walk-share 0.6 \
  --training-seed 2 --pressures-kpa 2.5 5 10 2>&1)"
rc=$?
if [[ $rc -ne 0 ]]; then
  fail "the bench with --fe-de-curve: exit $rc: $(tail -c 600 <<< "$out")"
elif ! grep -q "^# gonogo-bench-fe-ann: .*-pressure-scaled-3000pa" <<< "$out" ||
     ! grep -q "^held-out: triaxial 3.53553 kPa" <<< "$out"; then
  fail "the bench's model is not the recipe asked for: $(head -c 800 <<< "$out")"
elif ! grep -q "^fe-de curve: from $work/curve.csv (128 elements, 900 FE steps" <<< "$out" ||
     ! grep -qE "^fe-ann against fe-de, worst over the slips: drawbar pull [0-9.]+ % of W" \
       <<< "$out"; then
  fail "the bench did not compare with the file: $(tail -c 800 <<< "$out")"
else
  echo "ok: $(grep '^fe-ann against fe-de' <<< "$out")"
fi
if [[ "$(head -1 "$work/ann_samples.csv" 2>/dev/null)" != "$(head -1 "$work/samples.csv")" ]] ||
   [[ "$(wc -l < "$work/ann_samples.csv")" != "$(wc -l < "$work/samples.csv")" ]]; then
  fail "the bench's --samples-csv is not the fe-de records' columns and length"
else
  echo "ok: the fe-ann curve's records, $(wc -l < "$work/ann_samples.csv") lines as fe-de's"
fi

# 8. A bench run stopped part-way (--fe-ann-stop-at) still writes its rig records up to the stop:
#    the fe-de records' columns, from the run's start, fewer than a whole run's.
rm -f "$work/stopped_samples.csv"
out="$(timeout 600 "$bench" --no-fe-de --walks 2 --epochs 5 --threads 2 --fe-ann-stop-at 0.5 \
  --samples-csv "$work/stopped_samples.csv" 2>&1)"
rc=$?
stopped_lines="$(wc -l < "$work/stopped_samples.csv" 2>/dev/null || echo 0)"
if [[ $rc -ne 0 ]] || ! grep -q "curve: its rig records up to the stop" <<< "$out"; then
  fail "the stopped bench run: exit $rc, no records written: $(tail -c 600 <<< "$out")"
elif [[ "$(head -1 "$work/stopped_samples.csv")" != "$(head -1 "$work/samples.csv")" ]] ||
     [[ $stopped_lines -le 2 || $stopped_lines -ge $(wc -l < "$work/samples.csv") ]] ||
     [[ "$(sed -n 2p "$work/stopped_samples.csv" | cut -d, -f1-2)" != \
        "$(sed -n 2p "$work/samples.csv" | cut -d, -f1-2)" ]]; then
  fail "the stopped run's records are not the first of a run: $stopped_lines lines, $(head -2 "$work/stopped_samples.csv")"
else
  echo "ok: the stopped run's records, $stopped_lines lines of a whole run's $(wc -l < "$work/samples.csv")"
fi

if [[ $failures -gt 0 ]]; then
  echo "$failures failure(s)"
  exit 1
fi
echo "all passed"
