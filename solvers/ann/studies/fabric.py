#!/usr/bin/env python3
"""Does the packing's fabric separate what random walks and a rig's points teach the network?

Reads the histories `gonogo-ann --record-fabric --out DIR` wrote (training.npy with the
laboratory paths first, then the walks, then the rig's recorded paths; held_out.npy with the
held-out laboratory paths and walks first; every step also records the RVE's coordination number
Z and contact fabric F, trace 1) and trains, in Python's torch, one anchored MLP 64 x 64 as
history_variable.py does (inputs the strain increment, the stress before the step and the strain
accumulated since the path's start; output the stress increment after the Hughes-Winget rotation)
on

  - the laboratory paths and the first 12 walks, and
  - the laboratory paths and every walk,

each carrying nothing of the fabric (history_variable.py's network), Z and the deviatoric fabric
F - I/3 (their errors weighed in the loss as the stress's, or ten times as much), Z alone, or
F - I/3 alone: what it carries is further inputs (the state before the step)
and their increments further outputs (the fabric's after the same rotation as the stress), so that
a point carries its fabric as it carries its stress. It prints, per model, each
held-out path's replay error (in brackets: replayed on the recorded fabric, its own stress fed
back) and, over the 12 most loaded rig paths (none of them trained on), the stress error fed the
recorded stress and fabric before each step (one-step) and fed back its own (replay). Errors as ReplayError (solvers/ann/stress_surrogate.h): mean |sigma error| over
mean |sigma|, Frobenius norms, in %.

    python3 solvers/ann/studies/fabric.py DIR LAB_PATHS WALKS [SEED]

(LAB_PATHS: 16 for the recipe's default pressures; WALKS: gonogo-ann's --walks; SEED: torch's seed
for the initial weights and the batch order, 1 by default.) The first step of
every path is skipped: the histories do not hold the state before it.
"""
import sys

import numpy as np
import torch

from history_variable import HELD_OUT_PATHS, fit_paths, kinematics, study, tensor, voigt

FABRIC_COLUMNS = ['coordination_number', 'fabric_xx', 'fabric_yy', 'fabric_zz', 'fabric_yz',
                  'fabric_xz', 'fabric_xy']
# What of the fabric state a network carries (none, all of it, Z alone, the deviatoric fabric
# alone), and the weight of the carried outputs' squared errors in the loss (the stress's: 1).
CARRIED = {'nothing': ([], 1), 'Z and F': (list(range(7)), 1), 'Z': ([0], 1),
           'F': (list(range(1, 7)), 1), 'Z and F, their loss x10': (list(range(7)), 10)}


def paths_of(table, columns):
    """(strain increments, rotations, stresses, fabric states) per history of an .npy table;
    a fabric state is Z followed by the deviatoric fabric (Voigt, tensor components)."""
    where = [columns.index(name) for name in FABRIC_COLUMNS]
    out = []
    for h in np.unique(table[:, 0]):
        rows = table[table[:, 0] == h]
        steps = [kinematics(dH) for dH in rows[:, 2:11].reshape(-1, 3, 3)]
        fabric = rows[:, where].copy()
        fabric[:, 1:4] -= 1.0 / 3.0
        out.append((np.array([s[0] for s in steps]), [s[1] for s in steps], rows[:, 11:17],
                    fabric))
    return out


def rotated(r, stress, fabric):
    """The stress and the fabric state turned by the step's rotation (Z stays)."""
    turned = fabric.copy()
    turned[1:] = voigt(r @ tensor(fabric[1:]) @ r.T)
    return voigt(r @ tensor(stress) @ r.T), turned


def samples(path, carried):
    increments, rotations, stresses, fabrics = path
    inputs, targets = [], []
    accumulated = increments[0].copy()
    for s in range(1, len(stresses)):
        stress_turned, fabric_turned = rotated(rotations[s], stresses[s - 1], fabrics[s - 1])
        inputs.append(np.concatenate([increments[s], stresses[s - 1], accumulated,
                                      fabrics[s - 1][carried]]))
        targets.append(np.concatenate([stresses[s] - stress_turned,
                                       (fabrics[s] - fabric_turned)[carried]]))
        accumulated = accumulated + increments[s]
    return inputs, targets


def train(paths, carried, seed=1, weight=1):
    """history_variable.py's network; the loss weighs each carried output's (standardised)
    squared error by `weight`, the stress's by 1."""
    outputs = 6 + len(carried)
    return fit_paths(paths, lambda path: samples(path, carried), seed,
                     None if weight == 1 else [1] * 6 + [weight] * (outputs - 6))


def errors_pct(increments_of, path, carried):
    """(one-step, replay, replay fed the recorded fabric) stress errors along a path, % of its
    mean |sigma|; the last tells how much of the replay's error is the carried fabric's."""
    increments, rotations, stresses, fabrics = path
    accumulated = increments[0].copy()
    stress, fabric = stresses[0].copy(), fabrics[0].copy()
    stress_on_recorded = stresses[0].copy()
    one_step, replay, on_recorded = [], [], []
    for s in range(1, len(stresses)):
        r = rotations[s]
        fed_stress, _ = rotated(r, stresses[s - 1], fabrics[s - 1])
        x = [increments[s], stresses[s - 1], accumulated, fabrics[s - 1][carried]]
        fed = fed_stress + increments_of(np.concatenate(x))[:6]
        turned, _ = rotated(r, stress_on_recorded, fabrics[s - 1])
        x = [increments[s], stress_on_recorded, accumulated, fabrics[s - 1][carried]]
        stress_on_recorded = turned + increments_of(np.concatenate(x))[:6]
        stress_turned, fabric_turned = rotated(r, stress, fabric)
        x = [increments[s], stress, accumulated, fabric[carried]]
        answer = increments_of(np.concatenate(x))
        stress = stress_turned + answer[:6]
        fabric = fabric_turned.copy()
        fabric[carried] += answer[6:]
        accumulated = accumulated + increments[s]
        one_step.append(np.linalg.norm(tensor(fed - stresses[s])))
        replay.append(np.linalg.norm(tensor(stress - stresses[s])))
        on_recorded.append(np.linalg.norm(tensor(stress_on_recorded - stresses[s])))
    size = np.mean([np.linalg.norm(tensor(x)) for x in stresses[1:]])
    return tuple(100 * np.mean(e) / size for e in (one_step, replay, on_recorded))


def main():
    if len(sys.argv) not in (4, 5):
        sys.exit(__doc__)
    directory, lab_count, walk_count = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    seed = int(sys.argv[4]) if len(sys.argv) == 5 else 1
    torch.set_num_threads(2)
    columns = open(f'{directory}/training.npy.columns.txt').read().split()
    if any(name not in columns for name in FABRIC_COLUMNS):
        sys.exit('no fabric in training.npy: run gonogo-ann with --record-fabric')
    training = paths_of(np.load(f'{directory}/training.npy'), columns)
    held_out = paths_of(np.load(f'{directory}/held_out.npy'), columns)[:HELD_OUT_PATHS]
    study(training, held_out, lab_count, walk_count,
          lambda paths, option: train(paths, option[0], seed, option[1]),
          lambda model, path, option: errors_pct(model, path, option[0]),
          [(f'carrying {name:7s}', option) for name, option in CARRIED.items()])


if __name__ == '__main__':
    main()
