#!/usr/bin/env python3
"""Plots one run of the 2-D axis-tracking scenario (JAIF Sec. 7.1) as an SVG, in the style of the
papers' example-run figures: the true axis angle, the measurements, the Bingham filter's mode with
its 95 % interval, and the Kalman filter's estimate.

    usage: scripts/plot_run.py run.csv plot.svg

The CSV is what ``examples/c/axis_tracking run.csv`` writes (columns step, truth, measurement,
bingham_mode, bingham_lo95, bingham_hi95, kalman; angles in radians, each axis angle shifted by
a multiple of pi to lie within pi/2 of the truth). Only the standard library is used (the SVG is
written directly), so ``make demo`` needs nothing beyond Python 3.
"""

import math
import sys

from svg_plot import nice_ticks, read_columns

W, H = 900, 480
LEFT, RIGHT, TOP, BOTTOM = 70, 20, 40, 60

COLORS = {
    "truth": "#000000",
    "measurement": "#7f7f7f",
    "bingham": "#1f77b4",
    "band": "#1f77b4",
    "kalman": "#d62728",
}


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    c = read_columns(argv[1])
    deg = 180 / math.pi
    steps = c["step"]
    series = {k: [v * deg for v in c[k]] for k in c if k != "step"}
    ymin = min(min(series["bingham_lo95"]), min(series["truth"]), min(series["kalman"]))
    ymax = max(max(series["bingham_hi95"]), max(series["truth"]), max(series["kalman"]))
    # the measurements can be far off (36 degrees noise); clip them to a padded range
    pad = 0.08 * (ymax - ymin)
    ymin, ymax = ymin - pad, ymax + pad
    xmin, xmax = 0, max(steps)

    def sx(x):
        return LEFT + (x - xmin) / (xmax - xmin) * (W - LEFT - RIGHT)

    def sy(y):
        return TOP + (ymax - y) / (ymax - ymin) * (H - TOP - BOTTOM)

    out = []
    add = out.append
    add(
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
        f'viewBox="0 0 {W} {H}" font-family="Helvetica, Arial, sans-serif" font-size="13">'
    )
    add(f'<rect width="{W}" height="{H}" fill="white"/>')
    add(
        f'<text x="{W / 2}" y="22" text-anchor="middle" font-size="15">'
        "Axis tracking (d = 2), one run of the JAIF Sec. 7.1 scenario</text>"
    )
    # grid and ticks
    for t in nice_ticks(ymin, ymax):
        y = sy(t)
        add(f'<line x1="{LEFT}" y1="{y:.1f}" x2="{W - RIGHT}" y2="{y:.1f}" stroke="#e5e5e5"/>')
        add(f'<text x="{LEFT - 8}" y="{y + 4:.1f}" text-anchor="end">{t:g}</text>')
    for t in nice_ticks(xmin, xmax, 10):
        x = sx(t)
        add(f'<line x1="{x:.1f}" y1="{TOP}" x2="{x:.1f}" y2="{H - BOTTOM}" stroke="#e5e5e5"/>')
        add(f'<text x="{x:.1f}" y="{H - BOTTOM + 18}" text-anchor="middle">{t:g}</text>')
    add(
        f'<rect x="{LEFT}" y="{TOP}" width="{W - LEFT - RIGHT}" height="{H - TOP - BOTTOM}" '
        'fill="none" stroke="#333"/>'
    )
    add(f'<text x="{W / 2}" y="{H - 18}" text-anchor="middle">time step k</text>')
    add(
        f'<text transform="translate(18 {(TOP + H - BOTTOM) / 2}) rotate(-90)" '
        'text-anchor="middle">axis angle (degrees)</text>'
    )
    add(
        f'<clipPath id="plot"><rect x="{LEFT}" y="{TOP}" width="{W - LEFT - RIGHT}" '
        f'height="{H - TOP - BOTTOM}"/></clipPath><g clip-path="url(#plot)">'
    )
    # 95 % band of the Bingham filter
    upper = [(sx(x), sy(y)) for x, y in zip(steps, series["bingham_hi95"])]
    lower = [(sx(x), sy(y)) for x, y in zip(steps, series["bingham_lo95"])]
    pts = " ".join(f"{x:.1f},{y:.1f}" for x, y in upper + lower[::-1])
    add(f'<polygon points="{pts}" fill="{COLORS["band"]}" fill-opacity="0.18" stroke="none"/>')

    def line(key, color, width, dash=""):
        pts = " ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in zip(steps, series[key]))
        extra = f' stroke-dasharray="{dash}"' if dash else ""
        add(
            f'<polyline points="{pts}" fill="none" stroke="{color}" stroke-width="{width}"'
            f"{extra}/>"
        )

    for x, y in zip(steps, series["measurement"]):
        add(f'<circle cx="{sx(x):.1f}" cy="{sy(y):.1f}" r="2.2" fill="{COLORS["measurement"]}"/>')
    line("kalman", COLORS["kalman"], 1.6, "6 4")
    line("bingham_mode", COLORS["bingham"], 2.0)
    line("truth", COLORS["truth"], 1.6)
    add("</g>")
    # legend
    items = [
        ("truth", "line", COLORS["truth"], ""),
        ("measurements", "dot", COLORS["measurement"], ""),
        ("Bingham filter (mode)", "line", COLORS["bingham"], ""),
        ("Bingham 95 % interval", "band", COLORS["band"], ""),
        ("Kalman filter", "line", COLORS["kalman"], "6 4"),
    ]
    lx, ly = LEFT + 12, TOP + 14
    add(
        f'<rect x="{lx - 6}" y="{ly - 12}" width="205" height="{len(items) * 19 + 6}" '
        'fill="white" fill-opacity="0.85" stroke="#bbb"/>'
    )
    for i, (label, kind, color, dash) in enumerate(items):
        y = ly + i * 19
        if kind == "line":
            extra = f' stroke-dasharray="{dash}"' if dash else ""
            add(
                f'<line x1="{lx}" y1="{y}" x2="{lx + 26}" y2="{y}" stroke="{color}" '
                f'stroke-width="2"{extra}/>'
            )
        elif kind == "dot":
            add(f'<circle cx="{lx + 13}" cy="{y}" r="2.5" fill="{color}"/>')
        else:
            add(
                f'<rect x="{lx}" y="{y - 6}" width="26" height="12" fill="{color}" '
                'fill-opacity="0.18"/>'
            )
        add(f'<text x="{lx + 34}" y="{y + 4}">{label}</text>')
    add("</svg>")
    with open(argv[2], "w") as f:
        f.write("\n".join(out) + "\n")
    print(f"wrote {argv[2]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
