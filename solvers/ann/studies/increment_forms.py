#!/usr/bin/env python3
"""Can another form of network follow a rig point's small steps? Trains, in Python's torch, the
same three-member MLP (128 x 128 tanh, pressure-scaled at 3 kPa, carrying the coordination
number, the walks 60 % of the loss, Adam at 1e-3 halved at 50, 75 and 90 % of the epochs, batches
of 64) on the histories of DIR in one of three forms, and replays DIR's held-out paths open-loop
(the members' mean increment, the stress turned by each step's rotation, the admissible-stress cap
and cone), printing each path's error (mean |sigma error| over the path's mean |sigma|):

  smooth       the product's form (stress_surrogate.h): d_sigma = s (N(d_eps, ...) - N(0, ...)),
               s = max(p, 0) + 3 kPa. A smooth network answers an increment far smaller than its
               training steps linearly, so a step and its reverse alike but for the sign.
  homogeneous  d_sigma = s |d_eps| N(d_eps / |d_eps|, ...): positively homogeneous of degree one
               in the increment, as a rate-independent material's response to a small one is, so
               a loading and an unloading step may differ at any increment size.
  homlog       the same with log |d_eps| a further input: the stiffness may also vary with the
               step's size (a granular soil's stiffness falls as its strain amplitude grows).
  hybrid       the smooth form plus a homogeneous term of a second network of the same size:
               d_sigma = s (N(d_eps, ...) - N(0, ...) + |d_eps| M(d_eps / |d_eps|, ...)).
  hyblog       the hybrid with log |d_eps| a further input of its second network, so that its term
               may differ between a rig's steps and a walk's.
  unloading    the hybrid with its term gated to unloading: times u = max(0, -n : sigma / |sigma|),
               n = d_eps / |d_eps| (the work the step does on the stress, over its greatest:
               positive where the step loads, negative where it unloads, the shears' included), so
               that the smooth network alone answers a loading step.
  residual     the unloading form trained in two stages: the smooth network alone (as `smooth`),
               then, that network frozen, the gated term on what it leaves, so that a loading
               step is answered as by its smooth network alone.
  prevdir      the smooth form with the previous step's increment direction a further input
               (d_eps_(k-1) / |d_eps_(k-1)|, zero at a path's first step): a history variable a
               point can carry exactly. Along a rig path the steps turn little (the cosine of
               consecutive directions has median 0.999), so it tells a rig step whether it loads or
               unloads, and a smooth network may then answer the two with different stiffnesses;
               along a walk the steps are uncorrelated (median cosine 0.11), so the walks teach the
               response to a step after any other.
  shared       the same two terms from one network of twice the outputs, which sees the
               increment and its direction: d_sigma = s (A(x) - A(x_0) + |d_eps| B(x)), [A, B] =
               N(d_eps, d_eps / |d_eps|, ...), x_0 the same with no increment; as costly as the
               smooth form (two passes).

--step-size-weighting CAP weighs each step's squared error by (h_ref / |d_eps|)^2, at most CAP^2
(h_ref the training steps' median |d_eps|): each step's error relative to its own size, so that
a rig step (|d_eps| about 3e-6) counts as a walk's (about 8e-4) does.

DIR: the --out of `gonogo-ann --rig-load-n W --rig-points N --carry coordination_number`, whose
training.npy holds the recipe's 16 laboratory paths, then the walks, then the rig's paths, and
held_out.npy the recipe's held-out paths, then the rig's.

    python3 solvers/ann/studies/increment_forms.py DIR {smooth,homogeneous,homlog,hybrid,hyblog,unloading,residual,prevdir,shared}
        [--epochs 200] [--seed 2] [--members 3] [--step-size-weighting CAP] [--rig-weight R]
        [--term-penalty L] [--stiffness-only]

After the errors, each held-out rig path's steps answered one at a time from the RVE's own states
(step_stiffness.py's figures: the members' |d_sigma| over the RVE's, loading and unloading steps
apart).

(--stiffness-only: each path kind's median step size and median stiffness |d_sigma| / (s |d_eps|),
the ranges over its paths, and nothing trained.)
"""
import argparse
import os
import sys
import time

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from step_stiffness import step_inputs  # noqa: E402
from trajectory_spread import RIG_ROWS, Admissible, histories, kinematics, tensors, voigts  # noqa: E402

PRESSURE_REFERENCE_PA = 3000.0
WALK_SHARE = 0.6
LABORATORY_PATHS = 16  # the recipe's training paths before its walks


def strain_norm(d):
    """|d_eps| of (n, 6) Voigt strain rows with engineering shears, as (n, 1)."""
    return torch.sqrt((d[:, :3] ** 2).sum(1, keepdim=True) +
                      0.5 * (d[:, 3:] ** 2).sum(1, keepdim=True))


# The forms with the homogeneous term beside the smooth network, and those whose term is gated.
TERM_FORMS = ('hybrid', 'hyblog', 'unloading', 'residual')
GATED_FORMS = ('unloading', 'residual')


def unloading_gate(x):
    """max(0, -n : sigma / |sigma|) of raw input rows, (n, 1): n the increment's direction
    (engineering shears, so that n : sigma is the step's work on the stress), 1 where the step
    runs straight against the stress, 0 where it loads."""
    d, sigma = x[:, :6], x[:, 6:12]
    n = d / torch.clamp(strain_norm(d), min=1e-300)
    sigma_norm = torch.sqrt((sigma[:, :3] ** 2).sum(1, keepdim=True) +
                            2 * (sigma[:, 3:] ** 2).sum(1, keepdim=True))
    return torch.clamp(-(n * sigma).sum(1, keepdim=True) / torch.clamp(sigma_norm, min=1e-300),
                       min=0)


def pressure_scale(x):
    """s = max(p, 0) + p_ref of raw input rows [d_eps, sigma, eps, Z], as (n, 1)."""
    return torch.clamp(-x[:, 6:9].sum(1, keepdim=True) / 3, min=0) + PRESSURE_REFERENCE_PA


def with_previous_direction(x):
    """Raw input rows of one path in order, [d_eps, sigma_n, eps_n, Z_n], with the previous step's
    increment direction appended (zero at the first step and after a step that did not move)."""
    size = np.sqrt((x[:, :3] ** 2).sum(1) + 0.5 * (x[:, 3:6] ** 2).sum(1))[:, None]
    direction = np.where(size > 0, x[:, :6] / np.maximum(size, 1e-300), 0)
    return np.hstack([x, np.vstack([np.zeros(6), direction[:-1]])])


def steps_of(rows, z_column):
    """A history's raw inputs [d_eps, sigma_n, eps_n, Z_n, n_(k-1)] and changes [d_sigma, d_Z]."""
    increments, rotations = kinematics(rows[1:, 2:11].reshape(-1, 3, 3))
    before, after = rows[:-1, 11:17], rows[1:, 11:17]
    accumulated = np.vstack([np.zeros(6), np.cumsum(increments, 0)[:-1]])
    x = with_previous_direction(
        np.hstack([increments, before, accumulated, rows[:-1, z_column:z_column + 1]]))
    turned = voigts(rotations @ tensors(before) @ np.swapaxes(rotations, -1, -2))
    y = np.hstack([after - turned, rows[1:, z_column:z_column + 1] - rows[:-1, z_column:z_column + 1]])
    return x, y


def print_stiffness(training, is_walk, held_out, z_column):
    """Per path kind, the median step size |d_eps| and stiffness |d_sigma| / (s |d_eps|)."""
    def medians(rows):
        x, y = (torch.from_numpy(a) for a in steps_of(rows, z_column))
        size = strain_norm(x[:, :6])[:, 0]
        change = torch.linalg.norm(torch.from_numpy(tensors(y[:, :6].numpy())), dim=(-2, -1))
        moved = size > 0
        return (float(size.median()),
                float((change[moved] / (pressure_scale(x)[moved, 0] * size[moved])).median()))
    kinds = {'training walks': [r for r, w in zip(training, is_walk) if w],
             'training rig paths': [r for r in training if len(r) == RIG_ROWS],
             'held-out walks': [r for r in held_out[3:] if len(r) != RIG_ROWS],
             'held-out rig paths': [r for r in held_out if len(r) == RIG_ROWS]}
    for kind, paths in kinds.items():
        figures = np.array([medians(rows) for rows in paths])
        print(f'{kind} ({len(paths)}): median |d_eps| {figures[:, 0].min():.2g}-'
              f'{figures[:, 0].max():.2g}, median |d_sigma| / (s |d_eps|) '
              f'{figures[:, 1].min():.0f}-{figures[:, 1].max():.0f}')


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('directory')
    parser.add_argument('form', choices=['smooth', 'homogeneous', 'homlog', 'hybrid', 'hyblog',
                                         'unloading', 'residual', 'prevdir', 'shared'])
    parser.add_argument('--epochs', type=int, default=200)
    parser.add_argument('--seed', type=int, default=2)
    parser.add_argument('--members', type=int, default=3)
    parser.add_argument('--step-size-weighting', type=float, default=0, metavar='CAP')
    parser.add_argument('--rig-weight', type=float, default=1, metavar='R',
                        help="each training rig path's steps weigh R times a laboratory step")
    parser.add_argument('--term-penalty', type=float, default=0, metavar='L',
                        help="the hybrid forms' loss plus L times the term's mean square, in the "
                             "loss's units, so that the term stays where the fit needs it")
    parser.add_argument('--stiffness-only', action='store_true',
                        help="print the paths' step sizes and stiffnesses only, no training")
    args = parser.parse_args()
    if args.term_penalty > 0 and args.form not in TERM_FORMS:
        parser.error(f'--term-penalty: the {args.form} form has no homogeneous term')
    torch.set_num_threads(1)
    torch.set_default_dtype(torch.float64)
    directory, form = args.directory, args.form
    columns = open(f'{directory}/training.npy.columns.txt').read().split()
    z_column = columns.index('coordination_number')

    training = histories(np.load(f'{directory}/training.npy'))
    is_walk = [k >= LABORATORY_PATHS and len(rows) != RIG_ROWS for k, rows in enumerate(training)]
    if args.stiffness_only:
        print_stiffness(training, is_walk, histories(np.load(f'{directory}/held_out.npy')),
                        z_column)
        return
    walk_steps = sum(len(rows) - 1 for rows, walk in zip(training, is_walk) if walk)
    other_steps = sum(len(rows) - 1 for rows in training) - walk_steps
    walk_weight = WALK_SHARE / (1 - WALK_SHARE) * other_steps / walk_steps
    xs, ys, ws = [], [], []
    for rows, walk in zip(training, is_walk):
        x, y = steps_of(rows, z_column)
        xs.append(x)
        ys.append(y)
        rig = len(rows) == RIG_ROWS
        ws.append(np.full(len(x), walk_weight if walk else args.rig_weight if rig else 1.0))
    X, Y, W = (torch.from_numpy(np.concatenate(a)) for a in (xs, ys, ws))
    W = W / W.mean()
    step_reference = float(strain_norm(X[:, :6]).median())

    def features(x, form=form):
        if form == 'shared':
            return torch.cat([x[:, :6], features(x, 'homogeneous')], 1)
        d = x[:, :6]
        extra = []
        if form not in ('smooth', 'prevdir') and form not in TERM_FORMS:
            h = strain_norm(d)
            d = torch.where(h > 0, d / torch.clamp(h, min=1e-300), torch.zeros_like(d))
            if form == 'homlog':
                extra = [torch.log(torch.clamp(h, min=1e-12) / step_reference)]
        if form == 'prevdir':
            extra = [x[:, 19:25]]
        s = pressure_scale(x)
        return torch.cat([d, x[:, 6:12] / s, x[:, 12:19], torch.log(s / PRESSURE_REFERENCE_PA)] +
                         extra, 1)

    F = features(X)
    # what the hybrid's second network sees: the increment's direction (hyblog: and log |d_eps|)
    direction_form = 'homlog' if form == 'hyblog' else 'homogeneous'
    F_direction = features(X, direction_form)
    direction_mean, direction_scale_in = F_direction.mean(0), F_direction.std(0, unbiased=False)
    direction_scale_in[direction_scale_in < 1e-12] = 1
    T = torch.cat([Y[:, :6] / pressure_scale(X), Y[:, 6:]], 1)  # d_sigma / s, d_Z
    in_mean, in_scale = F.mean(0), F.std(0, unbiased=False)
    in_scale[in_scale < 1e-12] = 1
    out_scale = T.std(0, unbiased=False)
    magnitude = strain_norm(X[:, :6]) / step_reference
    direction_scale = (T / torch.clamp(magnitude, min=1e-12)).std(0, unbiased=False)

    class Member(torch.nn.Module):
        def __init__(self):
            super().__init__()
            outputs = T.shape[1] * (2 if form == 'shared' else 1)
            self.net = torch.nn.Sequential(
                torch.nn.Linear(F.shape[1], 128), torch.nn.Tanh(), torch.nn.Linear(128, 128),
                torch.nn.Tanh(), torch.nn.Linear(128, outputs))

            self.term_on = True
            if form in TERM_FORMS:
                self.direction_net = torch.nn.Sequential(
                    torch.nn.Linear(F_direction.shape[1], 128), torch.nn.Tanh(),
                    torch.nn.Linear(128, 128), torch.nn.Tanh(), torch.nn.Linear(128, T.shape[1]))

        def forward(self, f, x):  # in T's units
            if form == 'shared':
                rest = f.clone()
                rest[:, :6] = 0  # no increment, and so no direction
                rest[:, 6:12] = 0
                n = T.shape[1]
                at = self.net((f - in_mean) / in_scale)
                at_rest = self.net((rest - in_mean) / in_scale)
                return ((at[:, :n] - at_rest[:, :n]) * out_scale +
                        strain_norm(x[:, :6]) / step_reference * at[:, n:] * out_scale)
            if form in TERM_FORMS:
                rest = f.clone()
                rest[:, :6] = 0
                return ((self.net((f - in_mean) / in_scale) -
                         self.net((rest - in_mean) / in_scale)) * out_scale +
                        self.term(x))
            if form not in ('smooth', 'prevdir'):
                return (strain_norm(x[:, :6]) / step_reference *
                        self.net((f - in_mean) / in_scale) * direction_scale)
            rest = f.clone()
            rest[:, :6] = 0  # anchored: no increment, no change
            return (self.net((f - in_mean) / in_scale) -
                    self.net((rest - in_mean) / in_scale)) * out_scale

        def term(self, x):  # the hybrid's homogeneous term, in T's units
            direction = (features(x, direction_form) - direction_mean) / direction_scale_in
            gain = strain_norm(x[:, :6]) / step_reference
            if form in GATED_FORMS:
                gain = gain * unloading_gate(x)
            if not self.term_on:
                gain = gain * 0
            return gain * self.direction_net(direction) * out_scale

        def answer(self, x):  # d_sigma in Pa, d_Z
            t = self.forward(features(x), x)
            return torch.cat([t[:, :6] * pressure_scale(x), t[:, 6:]], 1)

    def train(seed):
        torch.manual_seed(seed)
        member = Member()
        if form == 'residual':  # the smooth network alone, then the gated term on its residual
            member.term_on = False
            fit(member, member.net.parameters())
            member.term_on = True
            for parameter in member.net.parameters():
                parameter.requires_grad_(False)
            fit(member, member.direction_net.parameters())
        else:
            fit(member, member.parameters())
        with torch.no_grad():
            return member, float((W[:, None] * ((member(F, X) - T) / out_scale) ** 2).mean())

    def fit(member, parameters):
        optimiser = torch.optim.Adam(parameters, lr=1e-3)
        for epoch in range(args.epochs):
            if epoch in (args.epochs // 2, args.epochs * 3 // 4, args.epochs * 9 // 10):
                for group in optimiser.param_groups:
                    group['lr'] /= 2
            order = torch.randperm(len(X))
            for start in range(0, len(X), 64):
                i = order[start:start + 64]
                error = (member(F[i], X[i]) - T[i]) / out_scale
                if args.step_size_weighting > 0:
                    error = error / torch.clamp(magnitude[i], min=1 / args.step_size_weighting)
                loss = (W[i, None] * error ** 2).mean()
                if args.term_penalty > 0:
                    loss = loss + args.term_penalty * (
                        W[i, None] * (member.term(X[i]) / out_scale) ** 2).mean()
                optimiser.zero_grad()
                loss.backward()
                optimiser.step()

    start = time.time()
    members = []
    for k in range(args.members):
        member, loss = train(args.seed + k)
        members.append(member)
        print(f'# member {k}: loss {loss:.4g} (unweighted by step size), {time.time() - start:.0f} s',
              flush=True)

    admissible = Admissible(X[:, 6:12].numpy())
    held_out = histories(np.load(f'{directory}/held_out.npy'))
    laboratory = [h for h in held_out if len(h) != RIG_ROWS]
    names = (['triaxial', 'simple shear', 'unload-reload'] +
             [f'walk {k + 1}' for k in range(len(laboratory) - 3)] +
             [f'rig point {k + 1}' for k in range(len(held_out) - len(laboratory))])
    figures = []
    for name, rows in zip(names, held_out):
        increments, rotations = kinematics(rows[1:, 2:11].reshape(-1, 3, 3))
        stress, z, accumulated = rows[0, 11:17].copy(), rows[0, z_column], np.zeros(6)
        replayed = []
        for step in range(len(increments)):
            previous = with_previous_direction(increments[max(step - 1, 0):step + 1])[-1, 6:]
            x = torch.from_numpy(
                np.hstack([increments[step], stress, accumulated, [z], previous])[None])
            with torch.no_grad():
                change = np.mean([m.answer(x).numpy() for m in members], 0)[0]
            turned = rotations[step] @ tensors(stress) @ rotations[step].T
            stress = admissible((voigts(turned) + change[:6])[None])[0]
            z += change[6]
            accumulated = accumulated + increments[step]
            replayed.append(stress.copy())
        recorded = rows[1:, 11:17]
        error = (np.linalg.norm(tensors(np.array(replayed) - recorded), axis=(-1, -2)).mean() /
                 np.linalg.norm(tensors(recorded), axis=(-1, -2)).mean())
        figures.append(f'{name} {100 * error:.2f} %')
    weighting = (f', step sizes weighed up to x{args.step_size_weighting:g}'
                 if args.step_size_weighting > 0 else '')
    if args.rig_weight != 1:
        weighting += f', rig steps weighed x{args.rig_weight:g}'
    if args.term_penalty > 0:
        weighting += f', term penalty {args.term_penalty:g}'
    print(f'{form}, {args.epochs} epochs, seed {args.seed}{weighting}: ' + ', '.join(figures))
    # step_stiffness.py's figures on the held-out rig paths: each step answered from the RVE's own
    # state, the members' |d_sigma| summed over the RVE's, loading and unloading steps apart.
    for name, rows in zip(names, held_out):
        if len(rows) != RIG_ROWS:
            continue
        inputs, rve, loading = step_inputs(rows, [z_column])
        inputs = with_previous_direction(inputs)
        with torch.no_grad():
            answer = np.mean([m.answer(torch.from_numpy(inputs)).numpy()[:, :6]
                              for m in members], 0)
        sums = [np.linalg.norm(answer[kind], axis=1).sum() / np.linalg.norm(rve[kind], axis=1).sum()
                for kind in (loading, ~loading)]
        print(f'  {name}, one step at a time: loading {sums[0]:.2f}, unloading {sums[1]:.2f} of '
              "the RVE's |d_sigma|")


if __name__ == '__main__':
    main()
