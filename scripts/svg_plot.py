"""What the SVG plot scripts (``plot_run.py``, ``plot_spin.py``) share: reading a CSV of numeric
columns and choosing axis ticks. Standard library only."""

import csv
import math


def read_columns(path):
    """The CSV at ``path`` as ``{column: [float, ...]}`` (a header row, then numbers)."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"{path}: no data")
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def nice_ticks(lo, hi, n=6):
    """About ``n`` round tick values (steps of 1, 2 or 5 times a power of ten) in [lo, hi]."""
    span = hi - lo
    raw = span / n
    mag = 10 ** math.floor(math.log10(raw))
    step = min((m * mag for m in (1, 2, 5, 10) if m * mag >= raw), default=10 * mag)
    first = math.ceil(lo / step) * step
    ticks = []
    t = first
    while t <= hi + 1e-9 * span:
        ticks.append(round(t, 10))
        t += step
    return ticks
