#!/usr/bin/env python3
"""The rig's 5 ms records so far of a checkpointed drawbar-pull run, as CSV.

A curve of hours (gonogo-fe-de --checkpoint-dir) keeps its records in its checkpoint's rig.state
(solvers/rig/wheel_rig.cc, RunStateBytes); this prints them with the columns of gonogo-fe-de
--samples-csv, so that the phases already run can be looked at while the rest runs:

    python3 solvers/rig/studies/checkpoint_records.py CHECKPOINT_DIR/rig.state > records.csv
"""
import struct
import sys

TAG = b"GNGRIG01"
HEADER = ("time_s,phase,slip,forward_speed_m_s,angular_speed_rad_s,drawbar_pull_n,torque_nm,"
          "vertical_force_n,sinkage_m")


class Reader:
    def __init__(self, data):
        self.data, self.at = data, 0

    def take(self, fmt):
        values = struct.unpack_from("<" + fmt, self.data, self.at)
        self.at += struct.calcsize("<" + fmt)
        return values

    def blob(self):
        (size,) = self.take("Q")
        self.at += size


def sample(reader):
    # RigSample as PutSample writes it: time, phase (int32), then slip, forward speed, angular
    # speed, drawbar pull, torque, vertical force, sinkage.
    (time_s, phase) = reader.take("di")
    return (time_s, phase) + reader.take("7d")


def records(path):
    with open(path, "rb") as f:
        reader = Reader(f.read())
    if reader.data[:8] != TAG:
        sys.exit(f"{path}: not a rig state (it does not start with {TAG.decode()})")
    reader.at = 8
    reader.blob()          # the run's fingerprint
    reader.take("Qi")      # checkpoint generation, next FE step
    reader.take("4d")      # hub height, vertical speed, position, towed spin
    reader.take("i")       # records in the partial sum
    sample(reader)         # the partial sum
    (count,) = reader.take("Q")
    return [sample(reader) for _ in range(count)]


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    print(HEADER)
    for t, phase, slip, v, omega, d, torque, fz, z in records(sys.argv[1]):
        print(f"{t:.4f},{phase},{slip:.4f},{v:.4f},{omega:.4f},{d:.2f},{torque:.2f},{fz:.2f},"
              f"{z:.5f}")


if __name__ == "__main__":
    main()
