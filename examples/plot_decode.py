"""Render a synthetic capture, decode it, and save the colour-coded maps.

The decoding stage: every camera pixel gets the projector column and row that lit it, or a reason
why it could not be decoded.

    python examples/plot_decode.py [out.png]    # default: a new temporary folder
"""

import sys
import tempfile
from pathlib import Path

from procam import decode, patterns, simulate
from procam.plots.decode import decode_figure, save_figure

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="procam-")) / "decode.png"
scene = simulate.with_board_pose(simulate.preset("paper"), simulate.RECOMMENDED_POSE)
stack, truth = simulate.render(scene, seed=0)                # (46, 800, 1280) uint8 + ground truth
ps = patterns.pattern_set(*truth["projector"]["size"])
maps = decode.decode(stack, ps)                              # col/row maps, validity, reasons
print(f"decoded {maps.valid.mean():.1%} of the pixels")
save_figure(decode_figure(maps, stack[ps.white], title="decoded projector coordinates"), out)
print(f"wrote {out}")
