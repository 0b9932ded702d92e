#!/usr/bin/env python3
"""Plots the simulated ping-pong spin tracking (Glover & Kaelbling 2013, Sec. 6, Figure 4) as an
SVG: the mean spin error and the 12-way spin classification rate against the frame number, for
QBF-2, QBF-2 with the oracle prior, the bank of 12 QBF-2, QBF-1 and EKF-2, with chance.

    usage: scripts/plot_spin.py spin.csv spin.svg

The CSV is what ``tests/glover_spin.rs`` writes when ``BINGHAM_SPIN_CSV`` is set (columns
frame, <method>_spin_err, <method>_class for each method, chance; errors in radians, rates as
fractions):

    BINGHAM_SPIN_CSV=spin.csv cargo test --release --test glover_spin
    python3 scripts/plot_spin.py $CARGO_TARGET_DIR/spin.csv docs/spin_tracking.svg

Only the standard library is used (the SVG is written directly; axis ticks and the CSV reader
shared with ``scripts/plot_run.py`` in ``scripts/svg_plot.py``).
"""

import math
import sys

from svg_plot import nice_ticks, read_columns

PANEL_W, H = 470, 450
LEFT, RIGHT, TOP, BOTTOM = 62, 16, 44, 150
W = 2 * PANEL_W

# (column prefix, label, colour, width, dash)
SERIES = [
    ("qbf2", "QBF-2", "#1f77b4", 2.4, ""),
    ("oracle", "QBF-2, oracle prior", "#1f77b4", 1.3, "5 3"),
    ("bank", "bank of 12 QBF-2", "#2ca02c", 1.8, ""),
    ("qbf1", "QBF-1 (observation differences)", "#ff7f0e", 1.8, ""),
    ("ekf2", "EKF-2", "#d62728", 1.8, ""),
    ("ekf2_reported", "EKF-2, reported interpretation", "#d62728", 1.3, "2 3"),
]


def panel(add, x0, c, frames, suffix, ylabel, title, ymax, chance=None):
    xmin, xmax = 0, max(frames)
    ymin = 0.0

    def sx(x):
        return x0 + LEFT + (x - xmin) / (xmax - xmin) * (PANEL_W - LEFT - RIGHT)

    def sy(y):
        return TOP + (ymax - y) / (ymax - ymin) * (H - TOP - BOTTOM)

    add(
        f'<text x="{x0 + (LEFT + PANEL_W - RIGHT) / 2}" y="24" text-anchor="middle" '
        f'font-size="15">{title}</text>'
    )
    for t in nice_ticks(ymin, ymax, 6):
        y = sy(t)
        add(
            f'<line x1="{x0 + LEFT}" y1="{y:.1f}" x2="{x0 + PANEL_W - RIGHT}" y2="{y:.1f}" '
            'stroke="#e5e5e5"/>'
        )
        add(f'<text x="{x0 + LEFT - 8}" y="{y + 4:.1f}" text-anchor="end">{t:g}</text>')
    for t in nice_ticks(xmin, xmax, 8):
        x = sx(t)
        add(
            f'<line x1="{x:.1f}" y1="{TOP}" x2="{x:.1f}" y2="{H - BOTTOM}" stroke="#e5e5e5"/>'
        )
        add(f'<text x="{x:.1f}" y="{H - BOTTOM + 18}" text-anchor="middle">{t:g}</text>')
    add(
        f'<rect x="{x0 + LEFT}" y="{TOP}" width="{PANEL_W - LEFT - RIGHT}" '
        f'height="{H - TOP - BOTTOM}" fill="none" stroke="#333"/>'
    )
    add(
        f'<text x="{x0 + (LEFT + PANEL_W - RIGHT) / 2}" y="{H - BOTTOM + 38}" '
        'text-anchor="middle">frame</text>'
    )
    add(
        f'<text transform="translate({x0 + 16} {(TOP + H - BOTTOM) / 2}) rotate(-90)" '
        f'text-anchor="middle">{ylabel}</text>'
    )

    def line(values, color, width, dash):
        pts = " ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in zip(frames, values))
        extra = f' stroke-dasharray="{dash}"' if dash else ""
        add(
            f'<polyline points="{pts}" fill="none" stroke="{color}" stroke-width="{width}"'
            f"{extra}/>"
        )

    if chance is not None:
        line(chance, "#7f7f7f", 1.3, "6 4")
    for key, _, color, width, dash in reversed(SERIES):
        line(c[f"{key}_{suffix}"], color, width, dash)


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    c = read_columns(argv[1])
    frames = c["frame"]
    out = []
    add = out.append
    add(
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
        f'viewBox="0 0 {W} {H}" font-family="Helvetica, Arial, sans-serif" font-size="13">'
    )
    add(f'<rect width="{W}" height="{H}" fill="white"/>')
    err_max = max(max(c[f"{k}_spin_err"]) for k, *_ in SERIES)
    err_max = math.ceil(err_max * 5) / 5
    panel(add, 0, c, frames, "spin_err", "mean spin error (rad)", "Spin error", err_max)
    panel(
        add,
        PANEL_W,
        c,
        frames,
        "class",
        "classification rate",
        "Spin classification (12 types)",
        1.0,
        chance=c["chance"],
    )
    # legend, below both panels
    items = [(label, color, width, dash) for _, label, color, width, dash in SERIES]
    items.append(("chance (1/12)", "#7f7f7f", 1.3, "6 4"))
    lx, ly = LEFT, H - BOTTOM + 58
    for i, (label, color, width, dash) in enumerate(items):
        x = lx + (i % 3) * 290
        y = ly + (i // 3) * 22
        extra = f' stroke-dasharray="{dash}"' if dash else ""
        add(
            f'<line x1="{x}" y1="{y}" x2="{x + 30}" y2="{y}" stroke="{color}" '
            f'stroke-width="{width}"{extra}/>'
        )
        add(f'<text x="{x + 38}" y="{y + 4}">{label}</text>')
    add(
        f'<text x="{W / 2}" y="{H - 10}" text-anchor="middle" font-size="11" fill="#555">'
        "Simulated ping-pong balls (Glover &amp; Kaelbling 2013, Sec. 6): 240 trajectories, "
        "12 spin types, 45-90 degrees per frame; tests/glover_spin.rs</text>"
    )
    add("</svg>")
    with open(argv[2], "w") as f:
        f.write("\n".join(out) + "\n")
    print(f"wrote {argv[2]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
