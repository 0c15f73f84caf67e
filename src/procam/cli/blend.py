"""``procam blend``: the blend masks of a rig's overlapping projectors from one rig pose (:mod:`procam.rig.blend`)."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app, fail, say, user_errors
from ._options import ForceOpt, number
from ._paths import output_dir, output_path


@app.command("blend")
@user_errors
def blend_cmd(
    pose: Path = typer.Argument(..., help="A rig pose folder (one pose folder per projector, docs/rigs.md), ideally "
                                          "of the bare projection surface."),
    out: Path = typer.Option(..., "-o", "--out", help="Output folder: alpha_<projector>.png (16-bit), "
                                                      "overlap_<projector>.png and blend.npz."),
    camera: str = typer.Option(None, "--camera", help="The camera whose view defines the overlap (default: the "
                                                      "reference camera)."),
    grid: int = typer.Option(8, "--grid", help="Projector pixels between the interpolation nodes."),
    force: ForceOpt = False,
):
    """Per projector, alpha per projector pixel that sums to 1 where the projectors overlap (docs/rigs.md)."""
    from .. import capture, decode
    from ..rig.blend import blend_masks, write_blend

    number(grid, "--grid", lo=1, hi=256, what="a grid spacing in projector pixels")
    if not capture.is_rig_pose(pose):
        fail(f"{pose}: not a rig pose folder (rig.json, or one sub-folder per projector); see docs/rigs.md")
    rig = capture.read_rig_pose(pose)
    cam = camera or rig.reference
    if cam not in rig.cameras:
        fail(f"--camera {cam!r}: not a camera of {pose} (cameras: {', '.join(rig.cameras)})")
    pairs = [p for p in rig.pairs if p.camera == cam]
    if len(pairs) < 2:
        fail(f"{pose}: camera {cam} sees {len(pairs)} projector(s); blending needs two or more")
    output_dir(out, "-o", "blend", force, inputs=(pose,))
    for name in [f"{k}_{p.projector}.png" for p in pairs for k in ("alpha", "overlap")] + ["blend.npz"]:
        output_path(out / name, "-o", (Path(name).suffix,), inputs=(pose,))  # each file, before any work
    maps, sizes = {}, {}
    for p in pairs:
        cap = capture.load_capture(p.folder)
        d = decode.decode(cap.stack, cap.pattern_set, extras=False)
        maps[p.projector] = (d.col, d.row)
        sizes[p.projector] = (cap.pattern_set.width, cap.pattern_set.height)
        say(f"{p.folder}: {p.projector} decoded on {(d.valid_col & d.valid_row).mean():.0%} of the camera image")
    b = blend_masks(maps, sizes, grid=grid)
    out.mkdir(parents=True, exist_ok=True)
    for path in write_blend(b, out):
        say(f"wrote {path}")
    for n in b.alpha:
        say(f"{n}: overlap on {b.overlap[n].mean():.0%} of its pixels, measured (seen by {cam}) on "
            f"{b.seen[n].mean():.0%}")
