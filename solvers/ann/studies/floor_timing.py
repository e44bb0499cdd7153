#!/usr/bin/env python3
"""Would a pressure floor that flags only unloading steps be cheaper?

The pressure floor (surrogate_ensemble.h) flags a point whose mean compression p is below the floor
before a step, and the point's RVE answers it from then on. A point near the surface that is only
pressed (the network answers loading well) might be left to the network until it unloads. Reads a
curve's fallback paths as `gonogo dataset export DATASET --format npy` wrote them (each the RVE's
answer to a fallen-back point's whole history; with --named TEXT only the paths whose name in
DATASET.paths.csv holds TEXT, e.g. one curve's "of 66,") and takes those whose first stress is below
FLOOR_KPA, the points a floor flags at their first step. For each it finds the first step at which
such a gate would flag it:

  - p falling: p below the floor and its trend falling (step_stiffness.pressure_trend);
  - q released: p below the floor and the deviatoric stress q more than RELEASE_KPA below its
    largest so far (the shear unloading a network answers too softly, rig point 2).

A fallback replays the point's history on its RVE, so a point flagged late costs its RVE the same
steps as one flagged at its first: only the points a gate never flags are saved.

    python3 solvers/ann/studies/floor_timing.py DATASET.npy FLOOR_KPA [--release-kpa 1]
        [--named TEXT]
"""
import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from step_stiffness import pressure_trend  # noqa: E402


def first(mask):
    return int(np.argmax(mask)) if mask.any() else None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('dataset', metavar='DATASET.npy')
    parser.add_argument('floor_kpa', type=float)
    parser.add_argument('--release-kpa', type=float, default=1.0)
    parser.add_argument('--named', default='', metavar='TEXT')
    args = parser.parse_args()
    table = np.load(args.dataset)
    floor_pa, release_pa = 1e3 * args.floor_kpa, 1e3 * args.release_kpa
    history = table[:, 0].astype(int)
    with open(args.dataset[:-len('.npy')] + '.paths.csv', newline='') as index_file:
        named = [int(row['history']) for row in csv.DictReader(index_file)
                 if args.named in row['path_name']]
    falling, released, steps = [], [], []
    for index in named:
        stress = table[history == index, 11:17]
        p = -stress[:, :3].mean(1)
        if p[0] >= floor_pa:
            continue
        deviator = stress[:, :3] - stress[:, :3].mean(1, keepdims=True)
        q = np.sqrt(1.5 * ((deviator ** 2).sum(1) + 2 * (stress[:, 3:] ** 2).sum(1)))
        below = p < floor_pa
        falling.append(first(below & (np.gradient(pressure_trend(stress)) < 0)))
        released.append(first(below & (np.maximum.accumulate(q) - q > release_pa)))
        steps.append(len(p))
    print(f'{len(steps)} paths start below {floor_pa / 1e3:g} kPa '
          f'({min(steps)}-{max(steps)} steps)')
    for name, flagged in (('p falling', falling),
                          (f'q released by {release_pa / 1e3:g} kPa', released)):
        at = np.array([s for s in flagged if s is not None])
        if len(at) == 0:
            print(f'  {name}: none flagged')
            continue
        print(f'  {name}: {len(at)} flagged, at steps {at.min()} / {np.median(at):.0f} / '
              f'{at.max()} (min / median / max); {len(flagged) - len(at)} never')


if __name__ == '__main__':
    main()
