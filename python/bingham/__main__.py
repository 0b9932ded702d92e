"""The command line: ``python -m bingham smooth FILE… --out DIR`` smooths recorded IMU logs with
the offline smoother (:func:`bingham.smooth`), one output file per input, in the input's format.

Input, per file:

* ``.npz``: arrays ``gyr`` (n×3, rad/s), ``acc`` (n×3, m/s²), optional ``mag`` (n×3, any unit),
  optional ``time`` (or ``t``; n, seconds, strictly increasing), optional ``sampling_rate``
  (Hz; or ``sample_time``, s);
* ``.csv``: a header row naming the columns ``gyr_x gyr_y gyr_z acc_x acc_y acc_z``, optional
  ``mag_x mag_y mag_z`` and ``time`` (or ``t``); other columns are ignored; an empty cell or
  ``nan`` is "no sample" (the whole row of that sensor then counts as missing).

The period: ``--rate HZ`` (or ``--sample-time S``), else the file's ``sampling_rate`` /
``sample_time``, else the median step of its timestamps; a file with none of them is an error.

Output, ``DIR/<name>`` in the input's format: ``quat`` (n×4, w x y z, sensor → world ENU),
``spread`` (n, rad), ``bias`` (n×3, rad/s) and, in ``.npz`` only, ``covariance`` (n×3×3, rad²),
plus ``time`` when the input had it; in ``.csv`` the columns ``[time] quat_w quat_x quat_y quat_z
spread bias_x bias_y bias_z``. ``--jobs N`` smooths N files at a time (threads: the library runs
without Python's lock); progress goes to stderr. Exit status 0 when every file was smoothed, 1
when one failed (the others are still written), 2 for a usage error.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import csv
import os
import sys
import threading
import time as _time
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from .smooth import Smoothed, smooth

_AXES = ("x", "y", "z")


def _period(args: argparse.Namespace, meta: Dict[str, float], t: Optional[np.ndarray]) -> float:
    if args.rate is not None:
        return 1.0 / float(args.rate)
    if args.sample_time is not None:
        return float(args.sample_time)
    if "sampling_rate" in meta:
        return 1.0 / float(meta["sampling_rate"])
    if "sample_time" in meta:
        return float(meta["sample_time"])
    if t is not None and len(t) > 1:
        return float(np.median(np.diff(t)).item())
    raise ValueError("no sample rate: give --rate HZ, or store sampling_rate or time in the file")


def _read_npz(path: str) -> Tuple[Dict[str, np.ndarray], Dict[str, float]]:
    with np.load(path) as d:
        arrays = {k: np.asarray(d[k], dtype=np.float64) for k in d.files}
    data: Dict[str, np.ndarray] = {}
    for k in ("gyr", "acc"):
        if k not in arrays:
            raise ValueError(f"{path}: no array '{k}'")
        data[k] = arrays[k]
    if "mag" in arrays:
        data["mag"] = arrays["mag"]
    for k in ("time", "t"):
        if k in arrays:
            data["time"] = arrays[k]
            break
    meta = {k: float(arrays[k]) for k in ("sampling_rate", "sample_time") if k in arrays}
    return data, meta


def _read_csv(path: str) -> Tuple[Dict[str, np.ndarray], Dict[str, float]]:
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise ValueError(f"{path}: empty file")
    head = [h.strip() for h in rows[0]]
    col = {h: i for i, h in enumerate(head)}

    def column(name: str) -> np.ndarray:
        i = col[name]
        out = np.empty(len(rows) - 1)
        for k, r in enumerate(rows[1:]):
            cell = r[i].strip() if i < len(r) else ""
            out[k] = float(cell) if cell else np.nan
        return out

    data: Dict[str, np.ndarray] = {}
    for s in ("gyr", "acc", "mag"):
        names = [f"{s}_{a}" for a in _AXES]
        if all(n in col for n in names):
            data[s] = np.stack([column(n) for n in names], axis=1)
        elif s != "mag":
            raise ValueError(f"{path}: no columns {' '.join(names)} in the header")
    for k in ("time", "t"):
        if k in col:
            data["time"] = column(k)
            break
    return data, {}


def _write(path: str, out: Dict[str, np.ndarray]) -> None:
    tmp = path + ".part"
    if path.endswith(".npz"):
        with open(tmp, "wb") as fh:
            if "time" in out:
                np.savez(fh, quat=out["quat"], spread=out["spread"], bias=out["bias"],
                         covariance=out["covariance"], time=out["time"])
            else:
                np.savez(fh, quat=out["quat"], spread=out["spread"], bias=out["bias"],
                         covariance=out["covariance"])
    else:
        names: List[str] = []
        cols: List[np.ndarray] = []
        if "time" in out:
            names.append("time")
            cols.append(out["time"][:, None])
        names += [f"quat_{c}" for c in "wxyz"] + ["spread"] + [f"bias_{a}" for a in _AXES]
        cols += [out["quat"], out["spread"][:, None], out["bias"]]
        table = np.hstack(cols)
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(names)
            for row in table:
                w.writerow([repr(float(x)) for x in row])
    os.replace(tmp, path)


def smooth_file(path: str, out_dir: str, args: argparse.Namespace) -> Tuple[str, int]:
    """Smooths one file into ``out_dir``; returns (output path, samples)."""
    if path.endswith(".npz"):
        data, meta = _read_npz(path)
    elif path.endswith(".csv"):
        data, meta = _read_csv(path)
    else:
        raise ValueError(f"{path}: not a .npz or .csv file")
    t = data.get("time")
    ts = _period(args, meta, t)
    r = smooth(data["gyr"], data["acc"], data.get("mag"), sample_time=ts, time=t, full=True)
    assert isinstance(r, Smoothed)
    out = {"quat": r.quat, "spread": r.spread, "bias": r.bias, "covariance": r.covariance}
    if t is not None:
        out["time"] = t
    target = os.path.join(out_dir, os.path.basename(path))
    _write(target, out)
    return target, len(r.quat)


class _Progress:
    """Files done out of the total on stderr: a bar redrawn in place on a terminal, one line per
    file otherwise; a note when a file starts that is long (over a million samples' worth of
    bytes)."""

    def __init__(self, total: int, quiet: bool) -> None:
        self.total, self.done, self.quiet = total, 0, quiet
        self.tty = sys.stderr.isatty()
        self.lock = threading.Lock()
        self.t0 = _time.perf_counter()

    def start(self, path: str) -> None:
        if self.quiet:
            return
        size = os.path.getsize(path) if os.path.exists(path) else 0
        if size > 50_000_000:
            with self.lock:
                sys.stderr.write(f"\nsmoothing {path} ({size / 1e6:.0f} MB) ...\n")

    def finish(self, line: str) -> None:
        with self.lock:
            self.done += 1
            if self.quiet:
                return
            elapsed = _time.perf_counter() - self.t0
            if self.tty:
                width = 30
                fill = int(width * self.done / self.total)
                bar = "#" * fill + "-" * (width - fill)
                sys.stderr.write(f"\r[{bar}] {self.done}/{self.total} files, {elapsed:.1f} s  {line[:60]:<60}")
                if self.done == self.total:
                    sys.stderr.write("\n")
            else:
                sys.stderr.write(f"[{self.done}/{self.total}] {line} ({elapsed:.1f} s)\n")
            sys.stderr.flush()


def _smooth_command(args: argparse.Namespace) -> int:
    os.makedirs(args.out, exist_ok=True)
    progress = _Progress(len(args.files), args.quiet)
    failed = 0

    def one(path: str) -> str:
        progress.start(path)
        target, n = smooth_file(path, args.out, args)
        return f"{path} -> {target}: {n} samples"

    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        futures = {pool.submit(one, p): p for p in args.files}
        for fut in concurrent.futures.as_completed(futures):
            path = futures[fut]
            try:
                progress.finish(fut.result())
            except Exception as e:  # noqa: BLE001 -- one bad file must not stop the others
                failed += 1
                progress.finish(f"{path}: FAILED")
                sys.stderr.write(f"error: {path}: {e}\n")
    return 1 if failed else 0


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bingham", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    sp = sub.add_parser(
        "smooth",
        help="smooth recorded IMU logs (offline smoother)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("files", nargs="+", metavar="FILE", help=".npz or .csv recordings")
    sp.add_argument("--out", required=True, metavar="DIR", help="output directory")
    sp.add_argument("--rate", type=float, metavar="HZ", help="sample rate (Hz)")
    sp.add_argument("--sample-time", type=float, metavar="S", help="sample period (s)")
    sp.add_argument("--jobs", type=int, default=1, metavar="N", help="files smoothed at a time")
    sp.add_argument("--quiet", action="store_true", help="no progress output")
    args = ap.parse_args(argv)
    if args.command == "smooth":
        return _smooth_command(args)
    return 2  # pragma: no cover (argparse requires a command)


if __name__ == "__main__":
    sys.exit(main())
