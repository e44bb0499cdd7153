#!/usr/bin/env python3
"""How stiffly does a model answer the rig's loading steps and its unloading steps?
For each rig path of DIR (the training and held-out histories of the tiny rig's length that
`gonogo-ann --rig-load-n W --rig-points N --carry ... --out DIR` wrote), every step is answered
one step at a time from the RVE's own recorded state (its stress, accumulated strain and carried
variables): the members' mean d_sigma of each saved ensemble MODEL (member_<k>.pt, TorchScript)
against the RVE's, sigma_(k+1) - R sigma_k R^T (R the step's rotation). A step is loading where
the RVE's mean stress p (compression positive), averaged over 31 steps, grows, unloading where it
falls. Per path
and per kind it prints the sum of the model's |d_sigma| over the sum of the RVE's (1: as stiff as
the RVE, below 1: softer), the share of the RVE's |d_sigma| along its own direction that the
model gives (sum of a . r / |r| over sum of |r|), and the one-step error, sum |a - r| / sum |r|.
    python3 solvers/ann/studies/step_stiffness.py DIR MODEL [MODEL ...]
"""
import os
import sys

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from trajectory_spread import (RIG_ROWS, histories, kinematics, load_members,  # noqa: E402
                               tensors, voigts)


TREND_STEPS = 31


def pressure_trend(stresses):
    """The mean stress p (compression positive) of (n, 6) Voigt stresses averaged over TREND_STEPS
    steps: its slope, not each step's sign, says loading or unloading, as the RVE's p jitters step
    to step."""
    p = -stresses[:, :3].sum(1) / 3
    return np.convolve(p, np.ones(TREND_STEPS) / TREND_STEPS, mode='same')


def rig_paths(directory, columns, carried):
    """(role, index, rows) of DIR's rig histories, training ones first."""
    paths = []
    for role in ('training', 'held_out'):
        rig = [rows for rows in histories(np.load(f'{directory}/{role}.npy')) if len(rows) == RIG_ROWS]
        paths += [(role, index + 1, rows) for index, rows in enumerate(rig)]
    return paths


def step_inputs(rows, carried_columns):
    """The network's raw inputs at each step from the recorded state, and the RVE's answers."""
    recorded = rows[:, 11:17]
    increments, rotations = kinematics(rows[1:, 2:11].reshape(-1, 3, 3))
    accumulated = np.vstack([np.zeros(6), np.cumsum(increments, 0)[:-1]])
    inputs = np.hstack([increments, recorded[:-1], accumulated, rows[:-1, carried_columns]])
    turned = voigts(rotations @ tensors(recorded[:-1]) @ np.transpose(rotations, (0, 2, 1)))
    answers = recorded[1:] - turned
    return inputs, answers, np.gradient(pressure_trend(recorded))[:-1] > 0


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    directory, models = sys.argv[1], sys.argv[2:]
    torch.set_num_threads(2)
    columns = open(f'{directory}/training.npy.columns.txt').read().split()
    loaded = [load_members(model) for model in models]
    ensembles = [(os.path.basename(model.rstrip('/')), members)
                 for model, (members, _) in zip(models, loaded)]
    carried = loaded[0][1]
    carried_columns = [columns.index(n) for n in carried]
    print(f'{len(ensembles)} models carrying {carried or "nothing"}; per path, loading / unloading '
          'steps: model |d_sigma| over the RVE\'s, the share along the RVE\'s, one-step error')
    for role, index, rows in rig_paths(directory, columns, carried):
        inputs, rve, loading = step_inputs(rows, carried_columns)
        rve_size = np.linalg.norm(rve, axis=1)
        direction = rve / np.maximum(rve_size, 1e-30)[:, None]
        print(f'{role} rig path {index}: {loading.sum()} loading, {(~loading).sum()} unloading '
              f'steps; the RVE\'s median |d_sigma| {np.median(rve_size):.1f} Pa')
        for name, members in ensembles:
            with torch.no_grad():
                answer = np.mean([m(torch.from_numpy(inputs)).numpy()[:, :6] for m in members], 0)
            figures = []
            for kind in (loading, ~loading):
                size = rve_size[kind].sum()
                stiffness = np.linalg.norm(answer[kind], axis=1).sum() / size
                along = (answer[kind] * direction[kind]).sum() / size
                error = np.linalg.norm(answer[kind] - rve[kind], axis=1).sum() / size
                figures.append(f'{stiffness:.2f} {along:+.2f} {error:.2f}')
            print(f'  {name}: loading {figures[0]}; unloading {figures[1]}')


if __name__ == '__main__':
    main()
