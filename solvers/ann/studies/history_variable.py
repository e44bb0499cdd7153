#!/usr/bin/env python3
"""Does a history variable separate what random walks and a rig's points teach the network?

Reads the histories `gonogo-ann --out DIR` wrote (training.npy with the laboratory paths first,
then the walks, then the rig's recorded paths; held_out.npy with the held-out laboratory paths and
walks first) and trains, in Python's torch, one anchored MLP 64 x 64 (the recipe's network:
inputs the strain increment, the stress before the step and the strain accumulated since the
path's start; output the stress increment after the Hughes-Winget rotation) on

  - the laboratory paths and the first 12 walks, and
  - the laboratory paths and every walk,

each with and without a history variable the network can carry without predicting it: the
largest mean stress so far, and the distance of the mean stress below it (kPa-scale, an
overconsolidation measure). It prints, per model, each held-out path's replay error and, over the
12 most loaded rig paths (none of them trained on), the error fed the recorded stress before each
step (one-step) and fed back its own (replay). Errors as ReplayError (solvers/ann/stress_surrogate.h):
mean |sigma error| over mean |sigma|, Frobenius norms, in %.

    python3 solvers/ann/studies/history_variable.py DIR LAB_PATHS WALKS

(LAB_PATHS: 16 for the recipe's default pressures; WALKS: gonogo-ann's --walks.) The first step of
every path is skipped: the histories do not hold the stress before it.
"""
import sys

import numpy as np
import torch

HELD_OUT_PATHS = 7  # the recipe's triaxial, simple shear, unload-reload and four walks
RIG_PATHS_CHECKED = 12
EPOCHS = 200
BATCH = 64


def kinematics(dH):
    """Hughes-Winget: the strain increment (Voigt, engineering shears) and the rotation of dH."""
    eye = np.eye(3)
    G = dH @ np.linalg.inv(eye + 0.5 * dH)
    strain, spin = 0.5 * (G + G.T), 0.5 * (G - G.T)
    rotation = np.linalg.inv(eye - 0.5 * spin) @ (eye + 0.5 * spin)
    voigt = np.array([strain[0, 0], strain[1, 1], strain[2, 2],
                      2 * strain[1, 2], 2 * strain[0, 2], 2 * strain[0, 1]])
    return voigt, rotation


def tensor(v):
    return np.array([[v[0], v[5], v[4]], [v[5], v[1], v[3]], [v[4], v[3], v[2]]])


def voigt(m):
    return np.array([m[0, 0], m[1, 1], m[2, 2], m[1, 2], m[0, 2], m[0, 1]])


def mean_stress_pa(sigma):  # compression positive
    return -(sigma[0] + sigma[1] + sigma[2]) / 3


def paths_of(table):
    """(strain increments, rotations, stresses after each step) per history of an .npy table."""
    out = []
    for h in np.unique(table[:, 0]):
        rows = table[table[:, 0] == h]
        steps = [kinematics(dH) for dH in rows[:, 2:11].reshape(-1, 3, 3)]
        out.append((np.array([s[0] for s in steps]), [s[1] for s in steps], rows[:, 11:17]))
    return out


def features(strain_increment, stress_before, accumulated, largest_mean, with_history):
    columns = [strain_increment, stress_before, accumulated]
    if with_history:
        columns.append([largest_mean, largest_mean - mean_stress_pa(stress_before)])
    return np.concatenate(columns)


def samples(path, with_history):
    increments, rotations, stresses = path
    inputs, targets = [], []
    accumulated = increments[0].copy()
    largest_mean = mean_stress_pa(stresses[0])
    for s in range(1, len(stresses)):
        rotated = voigt(rotations[s] @ tensor(stresses[s - 1]) @ rotations[s].T)
        inputs.append(features(increments[s], stresses[s - 1], accumulated, largest_mean,
                               with_history))
        targets.append(stresses[s] - rotated)
        accumulated = accumulated + increments[s]
        largest_mean = max(largest_mean, mean_stress_pa(stresses[s]))
    return inputs, targets


def fit(inputs, targets, seed=1, output_weights=None):
    """The anchored MLP: d = N(d_eps, ...) - N(0, ...), standardised inputs and outputs, the strain
    increment the first six inputs; output_weights (one per output) weigh the squared errors.
    Returns the map from one input row to its answer."""
    X, Y = torch.tensor(np.array(inputs)), torch.tensor(np.array(targets))
    x_mean, x_scale = X.mean(0), X.std(0).clamp_min(1e-30)
    y_scale = Y.std(0).clamp_min(1e-30)
    torch.manual_seed(seed)
    net = torch.nn.Sequential(torch.nn.Linear(X.shape[1], 64), torch.nn.Tanh(),
                              torch.nn.Linear(64, 64), torch.nn.Tanh(),
                              torch.nn.Linear(64, Y.shape[1])).double()
    optimiser = torch.optim.Adam(net.parameters(), 3e-3)
    weights = None if output_weights is None else torch.tensor(output_weights, dtype=torch.float64)
    xs, ys = (X - x_mean) / x_scale, Y / y_scale
    rest = X.clone()
    rest[:, :6] = 0
    xs_rest = (rest - x_mean) / x_scale
    for epoch in range(EPOCHS):
        if epoch in (EPOCHS // 2, 3 * EPOCHS // 4, 9 * EPOCHS // 10):
            for group in optimiser.param_groups:
                group['lr'] *= 0.5
        order = torch.randperm(len(X))
        for begin in range(0, len(X), BATCH):
            batch = order[begin:begin + BATCH]
            optimiser.zero_grad()
            squared = (net(xs[batch]) - net(xs_rest[batch]) - ys[batch]) ** 2
            loss = (squared if weights is None else squared * weights).mean()
            loss.backward()
            optimiser.step()

    def answer(x):
        with torch.no_grad():
            t = (torch.tensor(x)[None, :] - x_mean) / x_scale
            at_rest = t.clone()
            at_rest[0, :6] = -x_mean[:6] / x_scale[:6]
            return ((net(t) - net(at_rest)) * y_scale).numpy()[0]
    return answer


def fit_paths(paths, samples_of, seed=1, output_weights=None):
    """fit() on every step of `paths`, samples_of(path) -> (inputs, targets)."""
    inputs, targets = [], []
    for path in paths:
        x, y = samples_of(path)
        inputs += x
        targets += y
    return fit(inputs, targets, seed, output_weights)


def train(paths, with_history, seed=1):
    return fit_paths(paths, lambda path: samples(path, with_history), seed)


def errors_pct(stress_increment, path, with_history):
    """(one-step, replay) errors along a path, % of its mean |sigma|."""
    increments, rotations, stresses = path
    accumulated = increments[0].copy()
    replayed = stresses[0].copy()
    largest, largest_replayed = mean_stress_pa(stresses[0]), mean_stress_pa(stresses[0])
    one_step, replay = [], []
    for s in range(1, len(stresses)):
        r = rotations[s]
        fed = voigt(r @ tensor(stresses[s - 1]) @ r.T) + stress_increment(
            features(increments[s], stresses[s - 1], accumulated, largest, with_history))
        replayed = voigt(r @ tensor(replayed) @ r.T) + stress_increment(
            features(increments[s], replayed, accumulated, largest_replayed, with_history))
        accumulated = accumulated + increments[s]
        largest = max(largest, mean_stress_pa(stresses[s]))
        largest_replayed = max(largest_replayed, mean_stress_pa(replayed))
        one_step.append(np.linalg.norm(tensor(fed - stresses[s])))
        replay.append(np.linalg.norm(tensor(replayed - stresses[s])))
    size = np.mean([np.linalg.norm(tensor(x)) for x in stresses[1:]])
    return 100 * np.mean(one_step) / size, 100 * np.mean(replay) / size


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    directory, lab_count, walk_count = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    torch.set_num_threads(2)
    training = paths_of(np.load(f'{directory}/training.npy'))
    held_out = paths_of(np.load(f'{directory}/held_out.npy'))[:HELD_OUT_PATHS]
    study(training, held_out, lab_count, walk_count, train, errors_pct,
          [('history variable no ', False), ('history variable yes', True)])


def study(training, held_out, lab_count, walk_count, train, errors_pct, variants):
    """Splits the training paths (laboratory paths, walks, rig paths), trains each variant's
    network (train(paths, option)) on the laboratory paths with the first 12 walks and with every
    walk, and prints a row each: its held-out replays and its errors on the most loaded rig paths
    (errors_pct(model, path, option) -> (one-step, replay[, replay on the recorded state]))."""
    lab = training[:lab_count]
    walks = training[lab_count:lab_count + walk_count]
    rig = training[lab_count + walk_count:]
    if not rig:
        sys.exit('no rig paths in training.npy: run gonogo-ann with --rig-load-n')
    print(f'{len(lab)} laboratory paths, {len(walks)} walks, {len(rig)} rig paths; '
          f'{len(held_out)} held out')
    loaded = sorted(rig, key=lambda p: -np.abs(p[2]).max())[:RIG_PATHS_CHECKED]
    for name, paths in (('lab + 12 walks', lab + walks[:12]), (f'lab + {len(walks)} walks', lab + walks)):
        for label, option in variants:
            model = train(paths, option)
            held = [errors_pct(model, p, option)[1:] for p in held_out]
            on_rig = [errors_pct(model, p, option) for p in loaded]
            # A third error, where errors_pct gives one: the replay fed the recorded internal state.
            print(f'{name:16s} {label}: held-out replay '
                  + ' / '.join(f'{e[0]:.1f}' + (f' ({e[1]:.1f})' if len(e) > 1 else '')
                               for e in held)
                  + f' %; {len(loaded)} loaded rig paths: one-step '
                  f'{np.mean([e[0] for e in on_rig]):.1f} %, replay median '
                  f'{np.median([e[1] for e in on_rig]):.1f} %', flush=True)


if __name__ == '__main__':
    main()
