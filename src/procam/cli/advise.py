"""``procam advise``: live advice on the board's pose before a capture (preview window or JSON lines).

Importing this module registers the command on :data:`procam.cli._app.app`.  The advising session is
:class:`procam.acquire.live.LiveAdvice` (``procam capture --advise`` runs it before each pose too).
"""

from __future__ import annotations

import math
from typing import Optional

import typer

from ._app import app, fail, say, text_on_stderr, user_errors
from ._live import live_advice
from ._options import (
    BoardOpt,
    CameraSizeOpt,
    ExposureOpt,
    GainOpt,
    LiveAutoOpt,
    LiveCalibrationOpt,
    LiveJsonOpt,
    LiveMaxFramesOpt,
    LiveTargetOpt,
    SeedOpt,
    camera_settings,
    live_limits,
    parse_board,
)


def parse_angles(text: str, option: str) -> tuple[float, float, float]:
    """``"PSI,NU[,PHI]"`` degrees -> a tuple (one-line error naming ``option``)."""
    parts = [p for p in (text or "").replace(";", ",").split(",") if p.strip()]
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        vals = []
    if len(vals) not in (2, 3) or not all(math.isfinite(v) for v in vals):
        fail(f"{option} must be PSI,NU[,PHI] in degrees (e.g. 15,12,0), got {text!r}")
    if len(vals) == 2:
        vals.append(0.0)
    if any(abs(v) >= 80 for v in vals[:2]):
        fail(f"{option}: psi and nu must be within +-80 degrees, got {text!r}")
    return vals[0], vals[1], vals[2]


@app.command("advise")
@user_errors
def advise_cmd(
    board: BoardOpt,
    square: Optional[float] = typer.Option(None, "--square", help="Square size, the length unit of the advice's "
                                           "distances (default: the calibration's, else 1: lengths in squares)."),
    camera: str = typer.Option("opencv:0", "--camera", help="opencv:INDEX | genicam:PRODUCER.cti[#DEVICE] | virtual "
                               "(the simulator's view of the board under the projector's white light)."),
    calibration: LiveCalibrationOpt = None,
    json_lines: LiveJsonOpt = False,
    auto: LiveAutoOpt = False,
    max_frames: LiveMaxFramesOpt = None,
    target: LiveTargetOpt = 1.0,
    still: float = typer.Option(0.5, "--still", help="The board counts as still after this many seconds without "
                                "moving."),
    still_px: float = typer.Option(1.0, "--still-px", help="... moving more than this many pixels."),
    exposure: ExposureOpt = None,
    gain: GainOpt = None,
    camera_size: CameraSizeOpt = None,
    virtual_pose: Optional[str] = typer.Option(None, "--virtual-pose", help="--camera virtual: the board's angles "
                                               "PSI,NU[,PHI] in the camera frame (default: the recommended pose)."),
    seed: SeedOpt = 0,
):
    """Show the camera's live frames with the detected board, its angles in the camera (and, with a calibration
    that has R, T, in the projector), the predicted std of f_c and f_p for that pose, and which way to turn the
    board; Space/Enter or --auto ends it."""
    from ..acquire import cameras as cams
    from ..acquire.live import advisor_options, calibration_square, load_calibration_for

    if calibration is not None and square is None:
        square = calibration_square(calibration)
    b = parse_board(board, 1.0 if square is None else square)
    options = advisor_options(target, still, still_px)
    live_limits(max_frames)
    cam_size = camera_settings(exposure, gain, camera_size, seed)
    pose = parse_angles(virtual_pose, "--virtual-pose") if virtual_pose else None
    kind, _ = cams.parse_camera_spec(camera)
    if kind == "folder":
        fail(f"--camera {camera}: a folder camera delivers no live frames; advise needs a streaming camera "
             "(opencv:, genicam:) or virtual")
    if pose is not None and kind != "virtual":
        fail("--virtual-pose applies to --camera virtual only")
    calib, source = (None, "")
    if calibration is not None:
        calib, source = load_calibration_for(calibration, b)

    if kind == "virtual":
        from .. import simulate
        from ..acquire.cameras import VirtualLiveCamera

        scene = simulate.preset("ideal")
        if (b.cols, b.rows, b.square) != (scene.board_cols, scene.board_rows, scene.square):
            scene = scene.replace(board_cols=b.cols, board_rows=b.rows, square=b.square)
        scene = simulate.with_board_pose(scene, pose or simulate.RECOMMENDED_POSE)
        cam = VirtualLiveCamera(scene, seed=seed)
    else:
        cam = cams.open_camera(camera, size=cam_size, exposure_ms=exposure, gain=gain)
    session = live_advice(b, options, calibration=calib, source=source, json_lines=json_lines, auto=auto,
                          max_frames=max_frames)
    try:
        with cam, text_on_stderr(json_lines):
            res = session.run(cam)
    finally:
        session.close()
    a = res.advice
    if not json_lines:
        say(f"stopped ({res.reason}) after {res.frames} frames: {a.state}: {a.message}")
