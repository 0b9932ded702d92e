"""The AHRS's stated uncertainty against the truth (examples/python/ahrs_coverage.py): the share of
samples whose error lies within 1x and 2x the stated spread, per axis group, on the shared BROAD
trials and on the simulated suite (docs/accuracy/ahrs.md, "The stated uncertainty").

The issue's target is 0.50-0.85 within 1x and at least 0.95 within 2x. It is met on the suite in
every group and on BROAD in heading and total, and these tests assert it there. BROAD's tilt has
heavy tails (the reference's timing, docs/accuracy/ahrs.md note 8), and its bounds are the figures
measured, with a margin of a few hundredths.
"""

import glob
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "python"))
import ahrs_coverage  # noqa: E402
import ahrs_suite  # noqa: E402
import broad  # noqa: E402

TRIALS = sorted(glob.glob(os.path.join(broad.data_dir(None), "*.npz")))


def test_the_error_rotation_vector_is_the_world_frame_rotation_from_the_estimate():
    # q_true = exp(phi/2) ⊗ q_est for a known phi about the world's axes
    rng = np.random.default_rng(3)
    q = rng.normal(size=(50, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    phi = rng.normal(size=(50, 3)) * 0.3
    ang = np.linalg.norm(phi, axis=1)
    e = np.concatenate([np.cos(ang / 2)[:, None], np.sin(ang / 2)[:, None] * phi / ang[:, None]],
                       axis=1)
    truth = broad.qmul(e, q)
    assert np.allclose(ahrs_coverage.qlog_world(q, truth), phi, atol=1e-12)


def test_calibrated_draws_cover_as_a_normal_does():
    # the reference the coverage is compared with: one N(0, C) draw per sample, within 1x of a
    # one-dimensional spread 68 % of the time
    rng = np.random.default_rng(4)
    c = np.tile(np.diag([1e-4, 4e-4, 9e-4]), (20000, 1, 1))
    d = ahrs_coverage.calibrated_draws(c, rng)
    frac = np.mean(np.abs(d[:, 2]) <= 0.03)
    assert abs(frac - 0.6827) < 0.01, frac


@pytest.mark.skipif(len(TRIALS) != 9, reason="BROAD trials not found")
def test_broad_heading_and_total_are_near_calibrated():
    rows = [ahrs_coverage.broad_job((p, {})) for p in TRIALS]
    p = ahrs_coverage.pooled([r for r in rows if r["name"] not in ahrs_coverage.APART])
    # (within 1x, within 2x, calibrated 1x, calibrated 2x, RMS error / RMS spread)
    heading, tilt, total = p["heading"], p["tilt"], p["total"]
    # issue 34's target (0.5-0.85 within 1x, 0.95 within 2x), not far from the calibrated 0.68
    assert 0.60 <= heading[0] <= 0.85 and heading[1] >= 0.95, heading
    assert 0.60 <= total[0] <= 0.85 and total[1] >= 0.95, total
    # tilt: the right share within 1x, heavy tails within 2x (trials 02, 07, 09)
    assert 0.60 <= tilt[0] <= 0.75 and tilt[1] >= 0.85, tilt


def test_the_suite_meets_the_target_in_every_group():
    # the 44 scenarios with known truth (the 26 of the suite and the 18 of issue 34's
    # mechanisms): issue 34's target in heading, tilt and total. The 2x shares stand 0.004 to
    # 0.015 above it (docs/accuracy/ahrs.md, "The stated uncertainty", note 10); the tails are
    # the unobservable field offset and the long rejection with a gyroscope scale error
    jobs = [(n, ov, settle, {}) for n, _, ov, settle in ahrs_suite.scenarios()]
    assert len(jobs) == 44
    rows = [ahrs_coverage.sim_job(j) for j in jobs]
    p = ahrs_coverage.pooled(rows)
    for group in ("heading", "tilt", "total"):
        share = p[group]
        assert 0.5 <= share[0] <= 0.85 and share[1] >= 0.95, (group, share)
    # the spread moves with the error: segments' error and spread rank alike
    assert p["spearman"] > 0.4, p["spearman"]
