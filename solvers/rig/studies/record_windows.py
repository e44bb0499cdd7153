#!/usr/bin/env python3
"""Means of the rig's records over windows of time, side by side for several runs.

Reads record files with the columns of gonogo-rig drawbar --samples, gonogo-fe-de --samples-csv,
gonogo-bench-fe-ann --samples-csv or checkpoint_records.py, and prints for each window [from, to)
in seconds and each file: the records in it, mean drawbar pull D and torque T, the vertical force
F_z (mean, standard deviation, and the records below a tenth of the wheel load: the wheel off the
ground for most of those 5 ms) and the mean sinkage.

    python3 solvers/rig/studies/record_windows.py --load-n 1000 --windows 0.40:0.45 0.70:0.95 \\
        fe_de.csv fe_ann.csv
"""
import argparse
import csv
import statistics


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows or "vertical_force_n" not in rows[0]:
        raise SystemExit(f"{path}: no rig records (expected the columns of --samples-csv)")
    return [{k: float(v) for k, v in row.items()} for row in rows]


def window(text):
    try:
        start, end = (float(x) for x in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not FROM:TO in seconds")
    if not end > start:
        raise argparse.ArgumentTypeError(f"'{text}': TO must exceed FROM")
    return start, end


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--windows", type=window, nargs="+", required=True, metavar="FROM:TO")
    parser.add_argument("--load-n", type=float, required=True, help="the wheel load W, N")
    parser.add_argument("files", nargs="+")
    args = parser.parse_args()
    runs = [(path, read(path)) for path in args.files]
    for start, end in args.windows:
        print(f"{start:.3f}-{end:.3f} s:")
        for path, rows in runs:
            inside = [r for r in rows if start <= r["time_s"] < end]
            if not inside:
                print(f"  {path}: no records")
                continue
            def mean(column):
                return statistics.mean(r[column] for r in inside)

            fz = [r["vertical_force_n"] for r in inside]
            print(f"  {path}: {len(inside)} records, D {mean('drawbar_pull_n'):.1f} N, "
                  f"T {mean('torque_nm'):.2f} N m, "
                  f"F_z {statistics.mean(fz):.0f} N (sd {statistics.pstdev(fz):.0f} N, "
                  f"{sum(f < 0.1 * args.load_n for f in fz)} below W/10), "
                  f"sinkage {1e3 * mean('sinkage_m'):.2f} mm")


if __name__ == "__main__":
    main()
