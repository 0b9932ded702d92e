"""The offline smoother from Python: ``bingham.smooth`` against the truth of a simulated turn and
the online AHRS (the last sample has no future: it is the online estimate), its error model, and
the command line ``python -m bingham smooth`` (NPZ and CSV, several files, ``--jobs``, a bad file
reported while the others are written)."""

import math
import os
import subprocess
import sys

import numpy as np
import pytest

import bingham
from bingham.__main__ import main as cli_main

DT = 0.01


def turn(n=600, seed=1):
    """A level sensor turning about the vertical at 0.3 rad/s with a gyroscope bias of
    (0.002, -0.001, 0.003) rad/s and noise; truth q = (cos(ψ/2), 0, 0, sin(ψ/2)), ψ = 0.3 t."""
    rng = np.random.default_rng(seed)
    t = DT * np.arange(n)
    yaw = 0.3 * t
    gyr = np.tile([0.002, -0.001, 0.3 + 0.003], (n, 1)) + 0.002 * rng.standard_normal((n, 3))
    acc = np.tile([0.0, 0.0, 9.81], (n, 1)) + 0.03 * rng.standard_normal((n, 3))
    mag = np.stack([20 * np.sin(yaw), 20 * np.cos(yaw), -40 * np.ones(n)], axis=1)
    mag += 0.3 * rng.standard_normal((n, 3))
    truth = np.stack([np.cos(yaw / 2), 0 * yaw, 0 * yaw, np.sin(yaw / 2)], axis=1)
    return t, gyr, acc, mag, truth


def angle(q, truth):
    d = np.abs(np.sum(q * truth, axis=1)).clip(0, 1)
    return 2 * np.arccos(d)


def test_smooth_tracks_the_truth_and_ends_at_the_online_estimate():
    t, gyr, acc, mag, truth = turn()
    q, spread = bingham.smooth(gyr, acc, mag, sample_time=DT)
    assert q.shape == (len(t), 4) and spread.shape == (len(t),)
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0) and (q[:, 0] >= 0).all()
    assert angle(q, truth).max() < math.radians(2.0)
    online = bingham.Ahrs(DT).update_batch(gyr, acc, mag)
    assert np.array_equal(q[-1], online[-1])
    assert (spread > 0).all() and np.isfinite(spread).all()
    # the full result: the same quaternions; spread² the covariance's trace; timestamps uniform
    r = bingham.smooth(gyr, acc, mag, sample_time=DT, time=100.0 + t, full=True)
    assert np.array_equal(r.quat, q) and np.array_equal(r.spread, spread)
    assert r.bias.shape == (len(t), 3) and r.covariance.shape == (len(t), 3, 3)
    tr = np.trace(r.covariance, axis1=1, axis2=2)
    assert np.allclose(np.sqrt(tr), spread, rtol=1e-6)
    # without a magnetometer, overrides and AhrsParams accepted
    q6, _ = bingham.smooth(gyr, acc, None, sample_time=DT, acc_noise=0.02)
    assert np.isfinite(q6).all()
    q7, _ = bingham.smooth(gyr, acc, mag, params=bingham.AhrsParams.default(DT))
    assert np.array_equal(q7, q)


def test_smooth_errors():
    t, gyr, acc, mag, _ = turn(50)
    with pytest.raises(ValueError):
        bingham.smooth(gyr, acc[:-1], mag, sample_time=DT)
    with pytest.raises(ValueError):
        bingham.smooth(gyr, acc, mag, sample_time=100.0)  # a rate passed as the period
    bad = acc.copy()
    bad[0] = np.nan
    with pytest.raises(bingham.BinghamError, match="sample 0"):
        bingham.smooth(gyr, bad, mag, sample_time=DT)
    tt = t.copy()
    tt[10] = tt[9]
    with pytest.raises(bingham.BinghamError, match="timestamp"):
        bingham.smooth(gyr, acc, mag, sample_time=DT, time=tt)
    with pytest.raises(TypeError):
        bingham.smooth(gyr, acc, mag, sample_time=DT, no_such_field=1.0)
    q, s = bingham.smooth(np.zeros((0, 3)), np.zeros((0, 3)), sample_time=DT)
    assert q.shape == (0, 4) and s.shape == (0,)


def write_csv(path, t, gyr, acc, mag):
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("time,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z,comment\n")
        for k in range(len(t)):
            vals = [t[k], *gyr[k], *acc[k], *mag[k]]
            cells = ["" if np.isnan(v) else repr(float(v)) for v in vals]
            fh.write(",".join(cells) + ",x\n")


def test_command_line_npz_csv_jobs_and_a_bad_file(tmp_path, capsys):
    t, gyr, acc, mag, _ = turn(400)
    mag[100] = np.nan  # no magnetometer sample there
    np.savez(tmp_path / "a.npz", gyr=gyr, acc=acc, mag=mag, sampling_rate=1 / DT)
    write_csv(tmp_path / "b.csv", 5.0 + t, gyr, acc, mag)
    bad = acc.copy()
    bad[0] = np.nan
    np.savez(tmp_path / "c.npz", gyr=gyr, acc=bad, sampling_rate=1 / DT)
    out = tmp_path / "out"
    files = [str(tmp_path / n) for n in ("a.npz", "b.csv", "c.npz")]
    code = cli_main(["smooth", *files, "--out", str(out), "--jobs", "2", "--rate", "100"])
    assert code == 1  # c.npz failed
    err = capsys.readouterr().err
    assert "c.npz" in err and "sample 0" in err and "[3/3]" in err
    ref = bingham.smooth(gyr, acc, mag, sample_time=DT, full=True)
    with np.load(out / "a.npz") as a:
        assert np.array_equal(a["quat"], ref.quat) and np.array_equal(a["spread"], ref.spread)
        assert np.array_equal(a["bias"], ref.bias) and a["covariance"].shape == (400, 3, 3)
    rows = np.genfromtxt(out / "b.csv", delimiter=",", names=True)
    assert list(rows.dtype.names)[:6] == ["time", "quat_w", "quat_x", "quat_y", "quat_z", "spread"]
    refb = bingham.smooth(gyr, acc, mag, sample_time=DT, time=5.0 + t)
    q = np.stack([rows[f"quat_{c}"] for c in "wxyz"], axis=1)
    assert np.array_equal(q, refb[0]) and np.array_equal(rows["spread"], refb[1])
    assert not (out / "c.npz").exists()
    # the module runs as a program; a file without a rate is refused
    np.savez(tmp_path / "d.npz", gyr=gyr, acc=acc)
    env = dict(os.environ)
    r = subprocess.run([sys.executable, "-m", "bingham", "smooth", str(tmp_path / "d.npz"),
                        "--out", str(out)], capture_output=True, text=True, env=env)
    assert r.returncode == 1 and "rate" in r.stderr
    r = subprocess.run([sys.executable, "-m", "bingham", "smooth", str(tmp_path / "d.npz"),
                        "--out", str(out), "--rate", "100", "--quiet"],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 0 and r.stderr == ""
    with np.load(out / "d.npz") as d:
        assert np.array_equal(d["quat"], bingham.smooth(gyr, acc, sample_time=DT)[0])
