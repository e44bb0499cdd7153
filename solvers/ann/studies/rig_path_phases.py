#!/usr/bin/env python3
"""Where along a held-out rig path does a model's replay leave the RVE's stress?

Replays each held-out rig path of DIR (the histories of the tiny rig's length, its settled start
and 899 steps, in the held_out.npy that `gonogo-ann --rig-load-n W --rig-points N --carry ...
--out DIR` wrote) open-loop on the saved ensemble MODEL (member_<k>.pt, TorchScript): the
members' mean increment at the point's one stress, the stress turned by each step's rotation and
passed through the admissible-stress cap and cone (recomputed from DIR's training.npy, as
SurrogateEnsemble does), the carried variables advanced by the members' mean, strain-driven from
the recorded start; the same replay as `gonogo-ann`'s "open-loop" figure.

For each path it prints the replay's error (the mean |sigma error|, Frobenius, over the path's
mean |sigma|), split into its mean-stress part (sqrt(3) |p error|) and its deviatoric part
(|dev sigma error|), each over the same mean |sigma|; and then, every EVERY steps (60 unless
given), the recorded and the replayed mean stress p and deviatoric stress q = sqrt(3/2) |dev
sigma| (Pa), the carried variables, the |sigma error| and the accumulated volumetric strain and
shear (the sum of the steps' engineering shear magnitudes); and how far the network's answer to the
step's increment d and to its reverse -d are from being opposite, |a(d) + a(-d)| / |a(d)|, at the
step's own increment and at 100 times it (a smooth network answers an increment far smaller than
its training steps linearly: 0 there). Beside each path's error, the error of a replay that holds
the stress (each step only turns it): what a network that answered nothing would score.

    python3 solvers/ann/studies/rig_path_phases.py MODEL DIR [EVERY]
"""
import os
import sys

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from trajectory_spread import (RIG_ROWS, Admissible, histories, kinematics, load_members,  # noqa: E402
                               tensors, voigts)


def mean_and_deviatoric(voigt):
    """p (compression positive) and q of (n, 6) Voigt stresses, Pa."""
    t = tensors(voigt)
    p = -np.trace(t, axis1=-2, axis2=-1) / 3
    deviator = t + p[..., None, None] * np.eye(3)
    return p, np.sqrt(1.5 * (deviator * deviator).sum((-1, -2)))


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    model, directory = sys.argv[1:3]
    every = int(sys.argv[3]) if len(sys.argv) == 4 else 60
    torch.set_num_threads(2)
    members, carried = load_members(model)
    training = np.load(f'{directory}/training.npy')
    columns = open(f'{directory}/training.npy.columns.txt').read().split()
    carried_columns = [columns.index(n) for n in carried]
    admissible = Admissible(training[:, 11:17])
    rig = [rows for rows in histories(np.load(f'{directory}/held_out.npy'))
           if len(rows) == RIG_ROWS]
    print(f'{len(members)} members carrying {carried or "nothing"}; {len(rig)} held-out rig paths')

    shown = sorted(set(range(0, RIG_ROWS, every)) | {RIG_ROWS - 1})  # the table's rows

    def mean_answer(x):
        with torch.no_grad():
            return np.mean([m(torch.from_numpy(x)).numpy() for m in members], 0)

    for index, rows in enumerate(rig):
        recorded = rows[:, 11:17]
        recorded_carried = rows[:, carried_columns]
        increments, rotations = kinematics(rows[1:, 2:11].reshape(-1, 3, 3))
        stress = recorded[0].copy()
        variables = recorded_carried[0].copy()
        accumulated = np.zeros(6)
        replayed, replayed_carried = [stress.copy()], [variables.copy()]
        held = [stress.copy()]
        reverse = np.zeros((len(increments) + 1, 2))  # at the step's increment, and 100 times it
        for step in range(len(increments)):
            state = np.hstack([stress, accumulated, variables])
            x = np.hstack([increments[step], state])[None]
            answer = mean_answer(x)[0]
            for k, factor in enumerate((1, 100) if step + 1 in shown else ()):
                both = mean_answer(np.vstack([np.hstack([sign * factor * increments[step], state])
                                              for sign in (1, -1)]))[:, :6]
                reverse[step + 1, k] = np.linalg.norm(both.sum(0)) / np.linalg.norm(both[0])
            rotation = rotations[step]
            held.append(voigts(rotation @ tensors(held[-1]) @ rotation.T))
            stress = admissible((voigts(rotation @ tensors(stress) @ rotation.T) +
                                 answer[:6])[None])[0]
            variables = variables + answer[6:]
            accumulated = accumulated + increments[step]
            replayed.append(stress.copy())
            replayed_carried.append(variables.copy())
        replayed, replayed_carried = np.array(replayed), np.array(replayed_carried)

        error = tensors(replayed[1:] - recorded[1:])
        size = np.linalg.norm(tensors(recorded[1:]), axis=(-1, -2)).mean()
        p_error = -np.trace(error, axis1=-2, axis2=-1) / 3
        deviatoric_error = error + p_error[:, None, None] * np.eye(3)
        norm = np.linalg.norm(error, axis=(-1, -2))
        held_error = np.linalg.norm(tensors(np.array(held[1:]) - recorded[1:]), axis=(-1, -2))
        print(f'held-out rig path {index + 1}: from p {mean_and_deviatoric(recorded[:1])[0][0]:.0f} '
              f'Pa; error {100 * norm.mean() / size:.2f} % of its mean |sigma| ({size:.0f} Pa): '
              f'mean stress {100 * np.sqrt(3) * np.abs(p_error).mean() / size:.2f} %, deviatoric '
              f'{100 * np.linalg.norm(deviatoric_error, axis=(-1, -2)).mean() / size:.2f} %; '
              f'holding the stress {100 * held_error.mean() / size:.2f} %')
        p_recorded, q_recorded = mean_and_deviatoric(recorded)
        p_replayed, q_replayed = mean_and_deviatoric(replayed)
        volumetric = np.concatenate([[0], np.cumsum(increments[:, :3].sum(1))])
        shear = np.concatenate([[0], np.cumsum(np.linalg.norm(increments[:, 3:], axis=1))])
        names = ' '.join(f'{n} RVE / net' for n in carried)
        print(f'  step  p RVE / net, Pa   q RVE / net, Pa  {names}  |error|, Pa  eps_v  shear'
              f'  reverse x1 / x100')
        for step in shown:
            variables = ' '.join(f'{recorded_carried[step, k]:5.2f} / {replayed_carried[step, k]:5.2f}'
                                 for k in range(len(carried)))
            gap = norm[step - 1] if step > 0 else 0.0
            print(f'  {step:4d} {p_recorded[step]:7.0f} / {p_replayed[step]:7.0f} '
                  f'{q_recorded[step]:7.0f} / {q_replayed[step]:7.0f}  {variables}  {gap:8.0f}  '
                  f'{volumetric[step]:+.5f} {shear[step]:.5f}  '
                  f'{reverse[step, 0]:.4f} / {reverse[step, 1]:.4f}')


if __name__ == '__main__':
    main()
