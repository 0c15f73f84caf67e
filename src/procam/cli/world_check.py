"""``procam world-check``: project spots where the calibration puts the board's white squares, find them with the
camera, and say whether the calibration holds in the world (:mod:`procam.world_check`, docs/world-check.md).

Importing this module registers the command on :data:`procam.cli._app.app`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer

from ._app import app, fail, given, refuse, say, user_errors
from ._options import (
    _SIZE,
    BoardOpt,
    CameraSizeOpt,
    DisplayOpt,
    ExposureOpt,
    GainOpt,
    SeedOpt,
    SimPreset,
    SquareOpt,
    camera_settings,
    number,
    parse_board,
    parse_pose,
    real_camera,
    virtual_gain,
    value,
)
from ._paths import output_path


@app.command("world-check")
@user_errors
def world_check_cmd(
    calibration: Path = typer.Argument(..., help="The calibration to check (procam JSON or OpenCV YAML/XML)."),
    board: BoardOpt = None,
    square: SquareOpt = None,
    camera: str = typer.Option("opencv:0", "--camera", help="opencv:INDEX | genicam:PRODUCER.cti[#DEVICE] | "
                               "folder:PATH (see procam capture --list-devices)."),
    display: DisplayOpt = None,
    exposure: ExposureOpt = None,
    gain: GainOpt = None,
    camera_size: CameraSizeOpt = None,
    settle_ms: float = typer.Option(250.0, "--settle-ms", help="Wait after showing each image before grabbing, ms."),
    virtual: bool = typer.Option(False, "--virtual", help="No devices: the simulator's rig (--preset, the one "
                                 "procam capture --virtual captures) with the board at --pose shows and sees the "
                                 "spots; the calibration is checked against that rig."),
    preset: SimPreset = typer.Option(SimPreset.ideal, "--preset", help="--virtual: the simulator's rig."),
    pose: Optional[str] = typer.Option(None, "--pose", help="--virtual: board angles PSI,NU[,PHI] in degrees "
                                       "(camera frame; default: the recommended pose)."),
    seed: SeedOpt = 0,
    tolerance_px: float = typer.Option(0.5, "--tolerance-px", help="Holds when the RMS miss is at most this many "
                                       "camera px ..."),
    tolerance: Optional[float] = typer.Option(None, "--tolerance", help="... and at most this on the board, in the "
                                              "unit of --square (default: 1/50 of a square)."),
    png: Optional[Path] = typer.Option(None, "--png", help="Picture: the board, where each spot should be and where "
                                       "it landed, the misses magnified 10x."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="The numbers, per spot, as JSON."),
    wall: Optional[str] = typer.Option(None, "--wall", help="Also a COLSxROWS grid of spots over the projector's "
                                       "image, on the wall behind the board (the board's footprint left out), each "
                                       "checked against the line the calibration says it must fall on "
                                       "(docs/world-check.md), e.g. 8x5."),
):
    """Does the calibration hold in the world? Projects a spot onto the centre of each white square of the board
    in view, where the calibration says it is, finds the spots with the camera and reports how far each landed
    (camera px and board units), with a verdict: holds (exit 0), off or inconclusive (exit 3)."""
    from ..io import load_calibration
    from ..world_check import WorldCheckOptions

    number(settle_ms, "--settle-ms", lo=0, hi=10000, unit=" ms", what="a finite number")
    number(tolerance_px, "--tolerance-px", lo=0, lo_open=True, hi=1000, unit=" px", what="a finite number")
    number(tolerance, "--tolerance", lo=0, lo_open=True, what="a finite number")
    cam_size = camera_settings(exposure, gain, camera_size, seed, display)
    wall_grid = _wall_grid(wall) if wall is not None else None
    angles = parse_pose(pose) if pose is not None else None
    number(square, "--square", lo=0, lo_open=True, hi=1e9, what="a square size")
    if not virtual:
        for flag in given("pose", "preset", "seed"):
            fail(f"{flag} belongs to --virtual; add --virtual or leave it out")
        if board is None:
            fail("give the board in view: --board COLSxROWS (inner corners) and --square")
        real_camera(camera)
    else:
        refuse(("camera", "display", "camera_size", "exposure", "settle_ms"),
               "is a real device's setting; --virtual uses the simulator as the camera and projector")
        virtual_gain(gain)
    png = output_path(png, "--png", (".png", ".jpg", ".jpeg"), inputs=(calibration,))
    json_out = output_path(json_out, "--json", (".json",), inputs=(calibration,))
    if not calibration.is_file():
        what = "a folder, not a calibration file" if calibration.is_dir() else "no such calibration file"
        fail(f"{calibration}: {what}; give the file procam calibrate wrote")
    calib = load_calibration(calibration)
    if calib.projector is None or calib.R is None or calib.T is None:
        fail(f"{calibration}: a camera-only calibration (no projector, no R, T); the world check needs the "
             "projector's calibration too")
    options = WorldCheckOptions(tolerance_px=tolerance_px, tolerance=tolerance)

    if virtual:
        check = _virtual(calib, calibration, board, square, value(preset), angles, seed, gain, options, wall_grid)
    else:
        check = _devices(calib, parse_board(board, 1.0 if square is None else square), camera, display, cam_size,
                         exposure, gain, settle_ms, options, wall_grid)
    _report(check, png, json_out)


def _wall_grid(text: str) -> tuple[int, int]:
    """``--wall COLSxROWS`` -> (cols, rows), each from 2 to :data:`procam.world_check.WALL_GRID_MAX`."""
    from ..world_check import WALL_GRID_MAX

    m = _SIZE.match(text)
    if not m or not all(2 <= int(v) <= WALL_GRID_MAX for v in m.groups()):
        fail(f"--wall must look like COLSxROWS, each from 2 to {WALL_GRID_MAX} spots across the projector's image "
             f"(e.g. 8x5), got {text!r}")
    return int(m.group(1)), int(m.group(2))


def _virtual(calib, path, board, square, preset, angles, seed, gain, options, wall):
    """The check in the simulator's rig (its board unless --board), the board at ``angles``."""
    from ..acquire import cameras
    from ..board import Board
    from ..world_check import virtual_device, world_check

    scene = cameras.demo_scene(tuple(calib.projector.image_size), angles, preset)
    if gain is not None:
        scene = scene.replace(gain=scene.gain * float(gain))  # as the virtual camera's gain: a factor on the light
    if tuple(calib.camera.image_size) != tuple(scene.cam_size):
        fail(f"{path}: its camera is {calib.camera.image_size[0]}x{calib.camera.image_size[1]}, the simulator's rig "
             f"(--preset {preset}) has a {scene.cam_size[0]}x{scene.cam_size[1]} camera; --virtual checks a "
             "calibration of that rig (procam capture --virtual)")
    brd = parse_board(board, scene.square if square is None else square) if board else \
        Board(scene.board_cols, scene.board_rows, scene.square if square is None else square)
    if square is not None and abs(square - scene.square) > 1e-9 * scene.square:
        say(f"note: the simulator's board squares are {scene.square:g}; lengths are in units of --square {square:g}")
    return world_check(calib, brd, virtual_device(scene, seed), options=options, wall=wall)


def _devices(calib, brd, camera, display, cam_size, exposure, gain, settle_ms, options, wall):
    """The check with a projector window on ``display`` and the camera of the ``--camera`` spec."""
    from ..acquire.cameras import open_camera
    from ..acquire.projector import ProjectorWindow
    from ..world_check import capture_device, world_check

    with ProjectorWindow(tuple(calib.projector.image_size), display, title="procam world-check") as proj, \
            open_camera(camera, size=cam_size, exposure_ms=exposure, gain=gain) as cam:
        return world_check(calib, brd, capture_device(proj, cam, settle_ms / 1000.0), options=options, wall=wall)


def _report(check, png, json_out) -> None:
    """Print the verdict and the numbers; write the picture and the JSON; exit 3 unless the calibration holds."""
    from ..io.files import write_image, write_text
    from ..world_check import draw

    found = sum(s == "found" for s in check.status)
    say(f"spots: {found} of {len(check.status)} found (sigma {check.marker_sigma:.1f} projector px); "
        f"centroid noise {check.noise_px:.3f} px")
    say(f"miss: {check.rms_px:.3f} px RMS, {check.max_px:.3f} px max (camera); {check.rms:.4g} RMS, "
        f"{check.max:.4g} max (board units)")
    if check.wall is not None:
        w = check.wall
        say(f"wall: {w.n_found} of {len(w.status)} spots found, {w.rms_px:.3f} px RMS, {w.max_px:.3f} px max from "
            f"their epipolar lines (camera); rays {w.rms_gap:.4g} apart RMS (board units)")
    if png is not None:
        write_image(png, draw(check))
        say(f"picture: {png}")
    if json_out is not None:
        write_text(json_out, json.dumps(check.to_dict(), indent=1))
        say(f"numbers: {json_out}")
    if check.verdict != "holds":
        reason = "; ".join(check.reasons) + (f"; {check.diagnosis}" if check.diagnosis else "")
        fail(f"the calibration is {check.verdict} in the world: {reason}", code=3, label=check.verdict)
    say(f"verdict: holds - {check.reasons[0]}")
