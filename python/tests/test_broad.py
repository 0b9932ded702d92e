"""Regression test of the Bingham AHRS on the BROAD trials (real IMU data, optical truth).

Runs only when the trials are present (``$BROAD_DIR`` or ``../shared/data/broad`` beside the
repository). Asserts the documented accuracy of the default parameters: the mean total RMSE over
the nine trials within 5 % of the figure in docs/accuracy/ahrs.md, every trial better than Madgwick's
published figure on the same data, and the uncertainty readout's calibration.
Data: BROAD (Laidig, Caruso, Cereatti, Seel, Data 6(7):72, 2021, doi:10.3390/data6070072),
CC BY 4.0.
"""

import glob
import os
import sys

import pytest

# broad.py is an example program (examples/python/), not part of the package
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "python"))
import broad  # noqa: E402

# docs/accuracy/ahrs.md's figure for the default parameters (mean total RMSE over the nine trials, degrees).
DOCUMENTED_MEAN_TOTAL = 2.07
# What the peers achieve on the same nine trials (the data's README; reproduced by broad.py).
MADGWICK = {"02": 1.67, "07": 4.51, "09": 2.53, "11": 3.91, "16": 4.41, "25": 3.33,
            "27": 8.78, "30": 7.13, "34": 7.21}
VQF_MEAN = 2.28

DATA = broad.data_dir(None)
TRIALS = sorted(glob.glob(os.path.join(DATA, "*.npz")))

pytestmark = pytest.mark.skipif(len(TRIALS) != 9, reason=f"BROAD trials not found in {DATA}")


@pytest.fixture(scope="module")
def results():
    out = {}
    for path in TRIALS:
        res, _ = broad.evaluate((path, ["bingham"], False))
        assert not res["errors"], res["errors"]
        out[os.path.basename(path)[:2]] = res["filters"]["bingham"]
    return out


def test_mean_total_rmse_matches_documented_figure(results):
    mean = sum(r["total"] for r in results.values()) / len(results)
    assert abs(mean - DOCUMENTED_MEAN_TOTAL) <= 0.05 * DOCUMENTED_MEAN_TOTAL, mean
    # issue 20's acceptance: at most 0.95 of VQF's mean on the nine
    assert mean <= 0.95 * VQF_MEAN, mean


def test_every_trial_better_than_madgwick(results):
    for trial, r in results.items():
        assert r["total"] < MADGWICK[trial], (trial, r["total"])


def test_group_means_better_than_madgwick(results):
    undisturbed = [t for t in results if t in ("02", "07", "09", "11", "16")]
    disturbed = [t for t in results if t not in undisturbed]
    for group in (undisturbed, disturbed):
        ours = sum(results[t]["total"] for t in group) / len(group)
        theirs = sum(MADGWICK[t] for t in group) / len(group)
        assert ours < theirs, (group, ours, theirs)


def test_spread_is_calibrated_overall(results):
    # RMS of the actual error / RMS of the predicted spread, over the movement samples: the
    # median trial within [0.5, 2] and no trial but 27 overconfident (above 2). Per-trial figures
    # and the coverage per axis are in docs/accuracy/ahrs.md ("The stated uncertainty"); trial
    # 27's field is steadily off by ~7 degrees, an error no sensor here can see; the
    # translations 16 (0.2-0.3) and 11 (0.47 since the heading evidence follows the field's
    # deviation now, which lowered its error from 0.98 to 0.92 degrees) are over-covered: their
    # field's and accelerometer's variation along the motion widens the stated spread more than
    # their error.
    ratios = sorted(r["calibration_ratio"] for r in results.values())
    assert 0.5 <= ratios[len(ratios) // 2] <= 2.0, ratios
    over = {t for t, r in results.items() if r["calibration_ratio"] > 2.0}
    assert over <= {"27"}, ratios
    inside = {t for t, r in results.items() if 0.5 <= r["calibration_ratio"] <= 2.0}
    assert len(inside) >= 6, ratios
