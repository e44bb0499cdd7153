#!/usr/bin/env python3
"""Does the spread of the members' own trajectories say which rig points a network drifts on?

An ensemble answers a point's step with the mean of its members' stress increments, all taken at
the point's one stress, and flags the step when the members disagree about that increment (the
relative spread of surrogate_ensemble.h). Along a rig's 899 steps the answers drift far further
than one step's error, and a step's spread does not see it. Here each member also replays the
path on its own: its own stress and carried variables, its own answers. The spread of those
stresses is what the members disagree about after the whole history so far.

Reads the saved ensemble MODEL (member_<k>.pt, TorchScript; the admissible-stress cap and cone
recomputed from its training histories, as SurrogateEnsemble does) and the rig paths of DIR
(every history of the tiny rig's length, its settled start and 899 steps, in the training.npy
and held_out.npy that `gonogo-ann --rig-load-n W --rig-points N --carry ... --out DIR` wrote),
leaves out those in TRAINING (the model's own training.npy), and replays each remaining path,
strain-driven, from its recorded start:

  - shared:       the ensemble as the fe-ann tier runs it (the mean increment at one stress),
  - trajectories: each member on its own path, the answer the members' mean stress.

It prints each replay's error (mean |sigma error|, Frobenius, in kPa, and over the path's mean
|sigma|, in %), then how well three statistics rank the paths by the shared replay's error: the
largest one-step spread along the path (the tier's guard), the largest spread of the members'
stresses, and the largest distance of the shared replay's inputs from the training inputs (the
envelope, the Mahalanobis distance of surrogate_ensemble.h). For each, the share of the total
error (kPa, summed over paths) held by the paths it ranks worst, 4, 8 and 16 of them.

    python3 solvers/ann/studies/trajectory_spread.py MODEL TRAINING DIR
"""
import glob
import sys

import numpy as np
import torch

RIG_ROWS = 900  # the rig's histories: the settled start and 899 recorded steps
RIG_STEPS = RIG_ROWS - 1
FLAGGED = (4, 8, 16)
VOIGT_TO_TENSOR = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]


def tensors(v):
    """(n, 6) Voigt stresses -> (n, 3, 3)."""
    out = np.empty(v.shape[:-1] + (3, 3))
    for k, (i, j) in enumerate(VOIGT_TO_TENSOR):
        out[..., i, j] = v[..., k]
        out[..., j, i] = v[..., k]
    return out


def voigts(m):
    return np.stack([m[..., i, j] for i, j in VOIGT_TO_TENSOR], -1)


def kinematics(dH):
    """Hughes-Winget for (n, 3, 3) increments: strain increments (Voigt, engineering shears)
    and rotations."""
    eye = np.eye(3)
    G = dH @ np.linalg.inv(eye + 0.5 * dH)
    strain, spin = 0.5 * (G + np.swapaxes(G, -1, -2)), 0.5 * (G - np.swapaxes(G, -1, -2))
    rotation = np.linalg.inv(eye - 0.5 * spin) @ (eye + 0.5 * spin)
    v = voigts(strain)
    v[..., 3:] *= 2
    return v, rotation


def histories(table):
    return [table[table[:, 0] == h] for h in np.unique(table[:, 0])]


class Admissible:
    """SurrogateEnsemble::Admissible: principal stresses capped at the tensile limit, then
    returned radially in the deviatoric plane onto min c / max c >= k (c the compressions from
    the limit), the limit and k those of the training stresses above the stress floor."""

    def __init__(self, training_stresses):
        norms = np.linalg.norm(tensors(training_stresses), axis=(-1, -2))
        self.floor_pa = max(0.1 * norms.mean(), 1.0)
        principal = np.linalg.eigvalsh(tensors(training_stresses[norms >= self.floor_pa]))
        self.limit_pa = max(0.0, principal.max())
        c = self.limit_pa - principal
        self.k = (c.min(-1) / c.max(-1)).min()

    def __call__(self, stress):
        values, vectors = np.linalg.eigh(tensors(stress))
        c = np.maximum(self.limit_pa - values, 0.0)
        mean = c.mean(-1, keepdims=True)
        d = c - mean
        outside = (mean[:, 0] > 0) & (c.min(-1) < self.k * c.max(-1))
        with np.errstate(divide='ignore', invalid='ignore'):
            alpha = (1 - self.k) * mean[:, 0] / (self.k * d.max(-1) - d.min(-1))
        alpha = np.where(outside, np.clip(alpha, 0, 1), 1.0)
        c = mean + alpha[:, None] * d
        return voigts(vectors @ (np.eye(3) * (self.limit_pa - c)[:, None, :]) @
                      np.swapaxes(vectors, -1, -2))


def load_members(model):
    """The TorchScript members of the saved ensemble MODEL, and the variables they carry. These
    studies give a member the 18 + V smooth inputs; a network that also reads the previous step's
    direction (its attribute previous_direction) is refused, by name."""
    members = [torch.jit.load(f) for f in sorted(glob.glob(f'{model}/member_*.pt'))]
    if not members:
        sys.exit(f'{model}: no member_<k>.pt')
    if getattr(members[0], 'previous_direction', False):
        sys.exit(f'{model}: reads the previous step\'s direction (previous_direction), '
                 'six inputs this study does not build')
    return members, [n for n in members[0].carried_variables.split(',') if n]


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    model, training_file, directory = sys.argv[1:]
    torch.set_num_threads(2)
    members, carried = load_members(model)
    training = np.load(training_file)
    columns = open(f'{training_file}.columns.txt').read().split()
    carried_columns = [columns.index(n) for n in carried]
    admissible = Admissible(training[:, 11:17])

    # The envelope: inputs of every training step (the stress and variables before it).
    inputs = []
    for rows in histories(training):
        increments, _ = kinematics(rows[1:, 2:11].reshape(-1, 3, 3))
        accumulated = np.vstack([np.zeros(6), np.cumsum(increments, 0)[:-1]])
        inputs.append(np.hstack([increments, rows[:-1, 11:17], accumulated,
                                 rows[:-1][:, carried_columns]]))
    inputs = np.vstack(inputs)
    x_mean = inputs.mean(0)
    scale = inputs.std(0)
    scale[scale <= 0] = 1
    standard = (inputs - x_mean) / scale
    inverse = np.linalg.inv(np.cov(standard.T, bias=True) + 1e-6 * np.eye(inputs.shape[1]))

    def distance(x):
        d = (x - x_mean) / scale
        return np.sqrt(np.einsum('ni,ij,nj->n', d, inverse, d))

    # A rig path is told by its last stress (points at one depth start alike).
    trained_ends = {tuple(np.round(rows[-1, 11:17], 6)) for rows in histories(training)
                      if len(rows) == RIG_ROWS}
    rig = [rows for f in ('training.npy', 'held_out.npy')
           for rows in histories(np.load(f'{directory}/{f}'))
           if len(rows) == RIG_ROWS and tuple(np.round(rows[-1, 11:17], 6)) not in trained_ends]
    n = len(rig)
    recorded = np.stack([rows[:, 11:17] for rows in rig])          # (n, 900, 6)
    recorded_carried = np.stack([rows[:, carried_columns] for rows in rig])
    dH = np.stack([rows[1:, 2:11].reshape(-1, 3, 3) for rows in rig])  # (n, 899, 3, 3)
    print(f'{len(members)} members carrying {carried or "nothing"}; {n} rig paths not trained on; '
          f'tensile limit {admissible.limit_pa:.0f} Pa, k {admissible.k:.3f}, '
          f'stress floor {admissible.floor_pa:.0f} Pa')

    def answer(member, x):
        with torch.no_grad():
            return member(torch.from_numpy(x)).numpy()

    shared = recorded[:, 0].copy()
    shared_carried = recorded_carried[:, 0].copy()
    own = np.repeat(shared[None], len(members), 0)                 # (m, n, 6)
    own_carried = np.repeat(shared_carried[None], len(members), 0)
    accumulated = np.zeros((n, 6))
    step_spread = np.zeros(n)
    trajectory_spread = np.zeros(n)
    largest_distance = np.zeros(n)
    shared_error, own_error = np.zeros(n), np.zeros(n)
    for s in range(RIG_STEPS):
        increment, rotation = kinematics(dH[:, s])
        rotate = lambda v: voigts(rotation @ tensors(v) @ np.swapaxes(rotation, -1, -2))
        x = np.hstack([increment, shared, accumulated, shared_carried])
        answers = np.stack([answer(m, x) for m in members])        # (m, n, 6 + V)
        mean = answers.mean(0)
        largest_distance = np.maximum(largest_distance, distance(x))
        size = np.maximum.reduce([np.linalg.norm(tensors(shared), axis=(-1, -2)),
                                  np.linalg.norm(tensors(mean[:, :6]), axis=(-1, -2)),
                                  np.full(n, admissible.floor_pa)])
        step_spread = np.maximum(step_spread, answers[:, :, :6].std(0).max(-1) / size)
        shared = admissible(rotate(shared) + mean[:, :6])
        shared_carried = shared_carried + mean[:, 6:]
        for k, m in enumerate(members):
            a = answer(m, np.hstack([increment, own[k], accumulated, own_carried[k]]))
            own[k] = admissible(rotate(own[k]) + a[:, :6])
            own_carried[k] = own_carried[k] + a[:, 6:]
        accumulated = accumulated + increment
        trajectory_mean = own.mean(0)
        size = np.maximum(np.linalg.norm(tensors(trajectory_mean), axis=(-1, -2)),
                          admissible.floor_pa)
        trajectory_spread = np.maximum(trajectory_spread, own.std(0).max(-1) / size)
        truth = recorded[:, s + 1]
        shared_error += np.linalg.norm(tensors(shared - truth), axis=(-1, -2)) / RIG_STEPS
        own_error += np.linalg.norm(tensors(trajectory_mean - truth), axis=(-1, -2)) / RIG_STEPS
    path_size = np.linalg.norm(tensors(recorded[:, 1:]), axis=(-1, -2)).mean(1)

    for label, error in (('shared', shared_error), ('trajectories', own_error)):
        relative = 100 * error / path_size
        print(f'{label:13s} mean |error| {error.mean() / 1e3:.2f} kPa '
              f'(sum {error.sum() / 1e3:.0f}), worst {error.max() / 1e3:.2f} kPa; '
              f'relative median {np.median(relative):.1f} %, loaded half median '
              f'{np.median(relative[path_size >= np.median(path_size)]):.1f} %')
    order = np.argsort(-shared_error)
    print('share of the shared replay\'s summed error on the paths ranked worst by '
          + ', '.join(str(f) for f in FLAGGED))
    for label, statistic in (('the error itself', shared_error),
                             ('one-step spread', step_spread),
                             ('trajectory spread', trajectory_spread),
                             ('envelope distance', largest_distance)):
        ranked = np.argsort(-statistic)
        shares = [shared_error[ranked[:f]].sum() / shared_error.sum() for f in FLAGGED]
        ranks = lambda values: np.argsort(np.argsort(values))
        rank_corr = np.corrcoef(ranks(statistic), ranks(shared_error))[0, 1]
        print(f'  {label:18s} ' + ' / '.join(f'{100 * x:.0f} %' for x in shares)
              + f'; Spearman {rank_corr:.2f}; range {statistic.min():.3g}-{statistic.max():.3g}')
    print('worst 8 paths by the shared error: kPa, one-step spread, trajectory spread, distance')
    for p in order[:8]:
        print(f'  {shared_error[p] / 1e3:6.2f} kPa  {step_spread[p]:.3g}  '
              f'{trajectory_spread[p]:.3g}  {largest_distance[p]:.1f}')


if __name__ == '__main__':
    main()
