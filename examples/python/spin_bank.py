#!/usr/bin/env python3
"""Which way is it spinning? One spin filter against a bank of them (Glover & Kaelbling 2013).

    usage: python3 examples/python/spin_bank.py

The Python twin of ``examples/c/spin_bank.c``. An object (think of a ball with a logo) spins at a
constant rate, one of 12 spin types: 4 axes × 3 rates (45, 67.5, 90° per frame). A camera sees
its orientation every frame through Bingham noise with concentrations (−40, −40, −10), except
every 4th frame (the logo faces away: no observation), and cannot tell the logo from its 180°
turn about the body's z axis: each detection has two readings, ``y`` and ``y ∘ flip``, and each
filter takes the one with the higher predictive likelihood.

* QBF-2: one :class:`bingham.SpinFilter` with a broad spin prior at "no spin", (−3, −3, −3).
* The bank: one spin filter per spin type, its prior centred there ((−50)³). Every frame each
  member adds its predictive log-likelihood of the observation to a running sum; the bank's
  answer is the member with the largest sum (on frame 1 all tie: with a uniform orientation
  prior one observation says nothing about the spin).

The bank is an example, not library API: a list of filters and a running sum of
``SpinFilter.log_likelihood``; which priors, MAP or mixture weights, pruning and resetting are
the application's choices. Quaternions are scalar first ``(w, x, y, z)``;
``bh.quat_multiply(q, r)`` rotates by r, then by q. Output: frames 1, 2, 5, 10, 20, 40 of one
trajectory (BINGHAM_VERBOSE=1: frames 1 to 6 and every 5th), then the summary of 24 trajectories (2 of each spin type; the spin error's median and worst case: a
single filter now and then locks onto a wrong spin in the first frames, while the readings are
still ambiguous, and keeps it; the bank's summed likelihoods rule that out). The numbers are
those of the C program.

Needs the ``bingham`` Python package: ``pip install ./python`` from the repository root (``make
demo`` installs it into a virtual environment and runs this program with it).
"""

import math
import os
import sys

import numpy as np

try:
    import bingham as bh
except ImportError as e:
    sys.exit(f"{e}: install the bingham package first, `pip install ./python` from the repository root")

FRAMES, TRIALS = 40, 24
SHOW = 7  # the trajectory printed frame by frame
# BINGHAM_VERBOSE=1: frames 1 to 6 and every 5th of that trajectory, else frames 1, 2, 5, 10, 20, 40
VERBOSE = os.environ.get("BINGHAM_VERBOSE", "0") not in ("", "0")
AXES = {"x": [1, 0, 0], "y": [0, 1, 0], "z": [0, 0, 1], "xyz": [1, 1, 1]}
RATES_DEG = [45.0, 67.5, 90.0]
FLIP = np.array([0.0, 0.0, 0.0, 1.0])  # 180° about the body z axis


def rotation(axis, angle_deg):
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    h = math.radians(angle_deg) / 2
    return np.concatenate([[math.cos(h)], math.sin(h) * a])


def angle_deg(a, b):
    """The rotation angle between two rotations (q and −q are the same), degrees."""
    return math.degrees(2 * math.acos(min(1.0, abs(float(np.dot(a, b))))))


def centred(q, lam):
    """Bingham (m, z) with mode q, concentration −lam about it: columns q∘e1, q∘e2, q∘e3, q."""
    m = np.stack([bh.quat_multiply(q, e) for e in np.eye(4)[[1, 2, 3, 0]]], axis=1)
    return m, np.array([-lam, -lam, -lam, 0.0])


TYPES = [(name, rate) for name in AXES for rate in RATES_DEG]
SPINS = [rotation(AXES[name], rate) for name, rate in TYPES]
W = centred(np.array([1.0, 0, 0, 0]), 400.0)  # process noise on the spin, (−400)³
OBS = (W[0], np.array([-40.0, -40.0, -10.0, 0.0]))  # observation noise, less sure about z
BROAD = centred(np.array([1.0, 0, 0, 0]), 3.0)  # QBF-2's spin prior
UNIFORM = (np.eye(4), np.zeros(4))  # nothing known about the orientation


def pick(f, readings):
    """The reading the filter finds more probable, and its predictive log-likelihood."""
    lls = [f.log_likelihood(y, *OBS) for y in readings]
    i = int(np.argmax(lls))
    return readings[i], lls[i]


def run(trial, show):
    truth = trial % len(TYPES)
    spin = SPINS[truth]
    x = bh.sample(*UNIFORM, 1, seed=1000 + trial)[0]
    noise = bh.sample(*OBS, FRAMES, seed=2000 + trial)
    single = bh.SpinFilter(*UNIFORM, *BROAD)
    bank = [bh.SpinFilter(*UNIFORM, *centred(s, 50.0)) for s in SPINS]
    sums = np.zeros(len(bank))
    results = {}
    for frame in range(1, FRAMES + 1):
        x = bh.quat_multiply(spin, x)  # the object turns
        seen = frame % 4 != 0
        readings = None
        if seen:
            y = bh.quat_multiply(noise[frame - 1], x)  # y = o ∘ x
            readings = [y, bh.quat_multiply(y, FLIP)]  # the detector cannot tell y from y ∘ flip
        single.step(*W, pick(single, readings)[0] if seen else None, *OBS)
        for k, f in enumerate(bank):
            if seen:
                y, ll = pick(f, readings)
                sums[k] += ll
                f.step(*W, y, *OBS)
            else:
                f.step(*W)  # nothing observed: prediction only
        best = int(np.argmax(sums))
        err_single = angle_deg(single.spin_mode(), spin)
        err_bank = angle_deg(bank[best].spin_mode(), spin)
        results[frame] = (best == truth, err_single, err_bank)
        if show and (frame <= 6 or frame % 5 == 0 if VERBOSE else frame in (1, 2, 5, 10, 20, 40)):
            name, rate = TYPES[best]
            seen_text = "yes" if seen else "no"
            print(f"  {frame:5d}  {seen_text:4s}  {err_single:11.1f}  {name:>5s} {rate:4.1f}  {err_bank:10.1f}")
    return results


def main():
    name, rate = TYPES[SHOW % len(TYPES)]
    print(f"Which way is it spinning? One spin filter (QBF-2) vs a bank of {len(TYPES)}, "
          f"{TRIALS} trajectories of {FRAMES} frames")
    print(f"  one trajectory, true spin {name} {rate:.1f} deg/frame (spin errors in deg/frame)")
    print("  frame  seen  QBF-2 error  bank pick  bank error")
    runs = [run(t, show=t == SHOW) for t in range(TRIALS)]
    right = [sum(r[f][0] for r in runs) for f in (10, 20, 40)]
    print("  the bank picks the true spin type after 10 / 20 / 40 frames in "
          f"{right[0]} / {right[1]} / {right[2]} of {TRIALS} trajectories")
    single = [r[FRAMES][1] for r in runs]
    bank = [r[FRAMES][2] for r in runs]
    print(
        f"  spin error after {FRAMES} frames, median / worst: QBF-2 {np.median(single):.1f} / {max(single):.1f} deg, "
        f"bank {np.median(bank):.1f} / {max(bank):.1f} deg"
    )


if __name__ == "__main__":
    main()
