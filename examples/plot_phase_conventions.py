"""Draw the phase families' conventions (the figure of docs/patterns.md): where phase 0 is, which way it grows,
what projector pixel i means, how the frames of a block shift, and how a Gray code's stripes and the
complementary bit line up with the fringe periods.

The curves are procam's own patterns (:func:`procam.patterns.phase_set`, :meth:`PhaseSet.line`), so the figure
shows what ``procam patterns`` writes; the second panel is a description of another tool's convention
(:func:`procam.patterns.from_dict`).

    python examples/plot_phase_conventions.py [out.png]    # default: docs/phase-conventions.png
"""

import sys
from pathlib import Path

import numpy as np

from procam import patterns
from procam.plots import save_figure

P, N, WIDTH = 8, 4, 24
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "phase-conventions.png"

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ours = patterns.phase_set(WIDTH, 16, "gray-phase", steps=N, period=P, complementary=True)
theirs = patterns.from_dict({"family": "phase", "width": WIDTH, "height": 16,
                             "fringe": {"sign": -1, "origin": 0, "pixel_center": 0, "shift": -1, "start": -np.pi / 2},
                             "sequence": [{"kind": "phase", "axis": "col", "steps": N, "period": P},
                                          {"kind": "phase", "axis": "col", "steps": N, "period": 32},
                                          {"kind": "phase", "axis": "row", "steps": N, "period": P},
                                          {"kind": "phase", "axis": "row", "steps": N, "period": 32}]})

fig, axes = plt.subplots(2, 1, figsize=(11, 7.6), constrained_layout=True)
x = np.arange(WIDTH)
fine = np.linspace(-0.5, WIDTH - 0.5, 2000)
for ax, ps, title in ((axes[0], ours, "procam's sequences: sign +1, origin -0.5, pixel_center 0, shift +1, start 0 "
                                      f"(N = {N}, P = {P} px)"),
                      (axes[1], theirs, "described in patterns.json: sign -1, origin 0, pixel_center 0, shift -1, "
                                        "start -pi/2 (a sine)")):
    block = ps.phase_blocks("col")[-1]
    f = block.fringe
    for k, style in ((0, dict(color="tab:blue", lw=2.0)), (1, dict(color="tab:orange", lw=1.2, ls="--"))):
        _, line = ps.line(block.first + k)
        ax.step(x, line, where="mid", label=f"frame {k} of the block: the pixels' values", **style)
        t = 2 * np.pi * f.sign * (fine - f.x0) / block.period + block.shifts()[k]
        ax.plot(fine, 255 * f.shape(t), color=style["color"], lw=0.6, alpha=0.7)
    for edge in np.arange(-0.5, WIDTH, 1.0):
        ax.axvline(edge, color="0.88", lw=0.5, zorder=0)
    for m in range(-1, WIDTH // P + 2):
        x0 = f.x0 + m * P
        if -0.5 <= x0 <= WIDTH - 0.5:
            ax.axvline(x0, color="crimson", lw=1.2, ls=":")
            ax.text(x0 + 0.1, 262, "phase 0", color="crimson", fontsize=8)
    start = f.x0 if f.sign > 0 else f.x0 + P
    ax.annotate("", xy=(start + 0.75 * P * f.sign, -25), xytext=(start, -25),
                arrowprops=dict(arrowstyle="->", color="crimson"))
    ax.text(min(start, start + 0.75 * P * f.sign), -48, f"phase 0 -> 3/2 pi (sign {f.sign:+d}); frame k adds "
            f"{'+' if f.shift > 0 else '-'}2 pi k / N: the fringes move {'left' if f.shift * f.sign > 0 else 'right'}",
            color="crimson", fontsize=8)
    low = -60
    g = ps.gray_block("col")
    if g is not None:
        names = [f"Gray bit {g.bits - 1 - j}" for j in range(g.bits)] + ["complementary"]
        for j, name in enumerate(names):
            _, line = ps.line(g.first + 2 * j)
            y = -85 - 26 * j
            ax.fill_between(x, y, y + 16 * (line > 0), step="mid", color="0.35", lw=0)
            ax.text(-0.6, y + 3, name + "  ", fontsize=7, ha="right")
        low = -85 - 26 * len(names)
    ax.set_xticks(x)
    ax.set_yticks([0, 50, 100, 150, 200, 250])
    ax.set_xlim(-0.7, WIDTH - 0.3)
    ax.set_ylim(low, 285)
    ax.set_xlabel("projector coordinate x (pixel i is centred at x = i; grey lines: pixel edges)")
    ax.set_ylabel("pattern value")
    ax.set_title(title, fontsize=10)
    ax.legend(loc="upper right", fontsize=7, framealpha=0.9)
save_figure(fig, out)
print(f"wrote {out}")
