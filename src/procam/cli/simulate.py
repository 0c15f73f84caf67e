"""``procam simulate``: render a synthetic capture folder with ground truth."""

from __future__ import annotations

from pathlib import Path

import typer

from ..choices import PATTERN_ORDERS as ORDERS
from ..errors import OutputError
from ._app import app, console, fail, is_tty, refuse, say, user_errors, warn
from ._options import DeviceName, ForceOpt, SimPreset, number, parse_pose, pattern_sequence, value, with_pattern_options

#: Largest seed numpy's generators take from the CLI (2**32 - 1, as every procam command).
MAX_SEED = 2**32 - 1


@app.command("simulate")
@user_errors
@with_pattern_options(leave_out=("step",))
def simulate_cmd(
    out_dir: Path = typer.Argument(..., help="Output folder for the images, truth.json and patterns.json."),
    preset: SimPreset = typer.Option(SimPreset.paper, "--preset", help="Rig: paper (the paper's simulated procam), ideal "
                               "(u0p = W/2, alpha_p = 1, stronger lens distortion), lensshift (v0p beyond the "
                               "panel, projector lens distortion, a wall), hard (lenses OpenCV does not describe, "
                               "a room corner with objects), vertical (projector 0.6 m below the camera) or "
                               "ceiling (upside-down projector)."),
    pose: str = typer.Option(None, "--pose", help="Board angles PSI,NU,PHI in degrees (XYZ Euler, board -> "
                             "device; default: the recommended pose)."),
    frame: DeviceName = typer.Option(DeviceName.camera, "--frame", help="Device frame of --pose."),
    distance: float = typer.Option(None, "--distance", help="Board-centre depth in mm along the device's axis "
                                   "(default: the nearest that keeps the whole board in both images)."),
    noise: float = typer.Option(None, "--noise", help="Camera read noise in 8-bit DN (default 1.0); 0 renders "
                                "without any noise (no shot noise either)."),
    bits: int = typer.Option(8, "--bits", help="Output bit depth: 8 or 16."),
    seed: int = typer.Option(0, "--seed", help="Noise seed (same seed -> identical images)."),
    proj_gamma: float = typer.Option(None, "--proj-gamma", help="The projector's gamma: a pattern value v emits "
                                     "(v/255)^gamma of white (default 1, linear; fringes are distorted by it)."),
    rig: str = typer.Option(None, "--rig", help="Render a rig instead (two_projectors: one camera, two projectors "
                            "overlapping on a wall; two_cameras: one projector between two cameras) as a rig pose "
                            "folder: one pose folder per camera-projector pair, rig.json and the rig's truth.json "
                            "(Gray codes; --pose in the reference camera's frame; --preset and --frame do not apply)."),
    force: ForceOpt = False,
    **pattern_args,
):
    """Render a synthetic capture of a chessboard (Gray codes, or a phase family with --family), with its ground
    truth (truth.json)."""
    from .. import simulate as sim

    preset, frame, order, family = value(preset), value(frame), value(pattern_args["order"]), pattern_args["family"]
    if rig is not None and rig not in sim.RIG_PRESETS:
        fail(f"--rig must be one of {', '.join(sim.RIG_PRESETS)}, got {rig!r}")
    if rig is not None and frame != "camera":
        fail("--frame does not apply to a rig: --pose is in the reference camera's frame")
    if rig is not None:
        refuse(("preset",), f"chooses a camera-projector pair's rig; --rig {rig} renders its own devices")
    if preset not in sim.PRESETS:
        fail(f"--preset must be one of {', '.join(sim.PRESETS)}, got {preset!r}")
    if bits not in (8, 16):
        fail(f"--bits must be 8 or 16, got {bits}")
    if order not in ORDERS:
        fail(f"--order must be one of {', '.join(ORDERS)}, got {order!r}")
    if frame not in ("camera", "projector"):
        fail(f"--frame must be camera or projector, got {frame!r}")
    number(distance, "--distance", lo=50, hi=20000, unit=" mm", what="a board depth")
    number(noise, "--noise", lo=0, hi=255, unit=" DN (8-bit grey levels)", what="a read noise")
    number(seed, "--seed", lo=0, hi=MAX_SEED, what="a seed")
    number(proj_gamma, "--proj-gamma", lo=0.2, hi=5, what="a projector gamma")
    angles = parse_pose(pose) if pose is not None else sim.RECOMMENDED_POSE
    if rig is not None:
        from . import _rig

        if value(family) != "gray" or proj_gamma is not None:
            fail("--rig renders Gray codes with a linear projector: leave out --family and --proj-gamma")
        changes = {"bits": bits, **({} if noise is None else {"read_noise": noise})}
        if noise == 0:
            changes["full_well"] = 0.0
        try:
            return _rig.simulate(out_dir, rig, angles, distance, changes, seed, order, force)
        except OutputError as e:
            fail(str(e))
    from .. import capture

    scene = sim.preset(preset)
    ps = pattern_sequence(scene.proj_size, **pattern_args)
    try:
        capture.check_sequence_dir(out_dir, ps, writer="simulate", force=force, extra=("truth.json",),
                                   option="OUT_DIR")
    except OutputError as e:
        fail(str(e))
    if pose is not None or distance is not None or frame != "camera":
        scene = sim.with_board_pose(scene, angles, distance=distance, frame=frame)
    changes = {"bits": bits}
    if proj_gamma is not None:
        changes["proj_gamma"] = proj_gamma
    if noise is not None:
        changes["read_noise"] = noise
        if noise == 0:
            changes["full_well"] = 0.0
    scene = scene.replace(**changes)
    margin = sim.fit_margin(scene)

    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(TextColumn("[progress.description]{task.description}"), BarColumn(),
                  TextColumn("{task.completed}/{task.total}"), TimeElapsedColumn(),
                  console=console.real, transient=True, disable=not is_tty()) as bar:
        task = bar.add_task("rendering", total=1)

        def progress(done, total):
            bar.update(task, completed=done, total=total)

        stack, truth = sim.render(scene, order=ps, seed=seed, progress=progress)
        bar.update(task, description="writing")
        paths = sim.write_capture(out_dir, stack, truth, order=ps, force=force)

    pc, pp = truth["pose"]["camera"], truth["pose"]["projector"]
    what = f"order {order}" if value(family) == "gray" else ps.describe()
    say(f"wrote {len(paths)} images ({stack.shape[2]}x{stack.shape[1]}, {bits}-bit, {what}), "
        f"truth.json and patterns.json to {out_dir}")
    say(f"preset {preset}; board (psi, nu, phi) camera ({pc['angles_deg'][0]:.2f}, "
        f"{pc['angles_deg'][1]:.2f}, {pc['angles_deg'][2]:.2f}) deg, projector ({pp['angles_deg'][0]:.2f}, "
        f"{pp['angles_deg'][1]:.2f}, {pp['angles_deg'][2]:.2f}) deg; centre "
        f"({pc['t'][0]:.1f}, {pc['t'][1]:.1f}, {pc['t'][2]:.1f}) mm in the camera frame")
    if margin <= -1e8:
        warn("the board is not in view of both devices at this pose (outside an image or behind a device); "
             "the capture shows no usable board — try a larger --distance or smaller angles")
    elif margin < 0:
        warn(f"part of the board (with its margin) is outside the camera or projector image (by {-margin:.0f} px); "
             "some corners may be missing — try a larger --distance or smaller angles")
