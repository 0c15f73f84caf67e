"""``procam advise``: live advice on the board's pose before a capture (preview window or JSON lines).

Importing this module registers the command on :data:`procam.cli._app.app`.  The advising session is
:class:`procam.acquire.live.LiveAdvice` (``procam capture --advise`` runs it before each pose too).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer

from ._app import app, fail, refuse, say, text_on_stderr, user_errors
from ._live import live_advice
from ._options import (
    SIMULATED_CAMERA,
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
    refuse_unread_camera,
    seed_applies,
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
    mode: str = typer.Option("pose", "--mode", help="pose: advice on the board's pose before a capture; camera: "
                             "photos for a camera calibrated once (coverage, the next tilt, the predicted ± of f_c, "
                             "the principal point and the distortion after each photo, 'enough' at --f-target and "
                             "--pp-target), then it writes the camera file -o."),
    out: Optional[Path] = typer.Option(None, "-o", "--out", help="--mode camera: the camera file to write (.json), "
                                       "for 'procam calibrate POSE --camera FILE'."),
    f_target: float = typer.Option(0.2, "--f-target", help="--mode camera: enough when f_c is determined to this % "
                                   "of f_c."),
    pp_target: float = typer.Option(2.0, "--pp-target", help="--mode camera: ... and the principal point to this "
                                    "many pixels."),
    known_camera: Optional[Path] = typer.Option(None, "--known-camera", help="--mode pose: the camera file (procam "
                                                "advise --mode camera, calibrate --camera-only) the calibration will "
                                                "hold (calibrate POSE --camera FILE): the advice predicts the "
                                                "projector's ± for that fit; its R, T come from --calibration."),
):
    """Show the camera's live frames with the detected board, its angles in the camera (and, with a calibration
    that has R, T, in the projector), the predicted std of f_c and f_p for that pose, and which way to turn the
    board; Space/Enter or --auto ends it."""
    from ..acquire.live import advisor_options, calibration_square, load_calibration_for

    if mode not in ("pose", "camera"):
        fail(f"--mode must be pose or camera, got {mode!r}")
    if mode == "camera":
        if known_camera is not None:
            fail("--known-camera applies to --mode pose; the camera mode calibrates the camera itself")
        refuse(("target", "still", "still_px"), "is the pose advice's (--mode pose); the camera mode stops at "
                                                "--f-target and --pp-target")
        return _camera_mode(board, square, camera, json_lines, auto, max_frames, exposure, gain, camera_size,
                            virtual_pose, seed, out, f_target, pp_target, calibration)
    if out is not None:
        fail("-o writes the camera file of --mode camera; the pose mode writes nothing")
    refuse(("f_target", "pp_target"), "is when the camera mode (--mode camera) has photos enough")
    if calibration is not None and square is None:
        square = calibration_square(calibration)
    b = parse_board(board, 1.0 if square is None else square)
    options = advisor_options(target, still, still_px)
    live_limits(max_frames)
    opener = _camera_opener(camera, b, exposure, gain, camera_size, virtual_pose, seed, square)
    calib, source = (None, "")
    if calibration is not None:
        calib, source = load_calibration_for(calibration, b)
    cam = opener(None)
    known = None
    if known_camera is not None:
        from ..io import load_calibration

        known = load_calibration(known_camera).camera
    session = live_advice(b, options, calibration=calib, source=source, json_lines=json_lines, auto=auto,
                          max_frames=max_frames, known_camera=known, known_source=str(known_camera or ""))
    try:
        with cam, text_on_stderr(json_lines):
            res = session.run(cam)
    finally:
        session.close()
    a = res.advice
    if not json_lines:
        say(f"stopped ({res.reason}) after {res.frames} frames: {a.state}: {a.message}")


def _camera_opener(camera, b, exposure, gain, camera_size, virtual_pose, seed, square):
    """The live camera's options checked (before any other work); returns ``open(default_pose, **scene_changes)``,
    which opens it: the simulator's ``ideal`` rig with the board ``b`` at ``--virtual-pose`` (or ``default_pose``,
    or the recommended pose) for ``virtual``, else the device.  ``square``: the square size given (None: the
    simulated board keeps its own, the advice's lengths are in squares)."""
    from ..acquire import cameras as cams

    cam_size = camera_settings(exposure, gain, camera_size, seed)
    pose = parse_angles(virtual_pose, "--virtual-pose") if virtual_pose else None
    kind, _ = cams.parse_camera_spec(camera)
    if kind == "folder":
        fail(f"--camera {camera}: a folder camera delivers no live frames; advise needs a streaming camera "
             "(opencv:, genicam:) or virtual")
    if pose is not None and kind != "virtual":
        fail("--virtual-pose applies to --camera virtual only")
    if kind == "virtual":
        refuse(("camera_size", "exposure", "gain"), SIMULATED_CAMERA)
    else:
        refuse(("seed",), seed_applies("--camera virtual"))
    refuse_unread_camera(camera)

    def open_(default_pose, **changes):
        if kind != "virtual":
            return cams.open_camera(camera, size=cam_size, exposure_ms=exposure, gain=gain)
        from .. import simulate
        from ..acquire.cameras import VirtualLiveCamera

        scene = simulate.preset("ideal")
        size = (b.cols, b.rows, scene.square if square is None else b.square)
        if size != (scene.board_cols, scene.board_rows, scene.square):
            scene = scene.replace(board_cols=size[0], board_rows=size[1], square=size[2])
        scene = simulate.with_board_pose(scene, pose or default_pose or simulate.RECOMMENDED_POSE)
        return VirtualLiveCamera(scene.replace(**changes) if changes else scene, seed=seed)

    return open_


def _camera_mode(board, square, camera, json_lines, auto, max_frames, exposure, gain, camera_size, virtual_pose, seed,
                 out, f_target, pp_target, calibration):
    """``procam advise --mode camera``: the camera mode's loop (:func:`procam.acquire.live.advise_camera`), one
    line per frame (JSON with --json), then the camera file -o: written when the photos determine the camera to
    the targets (exit 0), written and exit 3 when two or more photos do not, nothing written before two."""
    from dataclasses import replace

    from ..acquire.live import advise_camera, camera_calibration
    from ..advisor import AdvisorOptions, CameraAdvisor
    from ._paths import output_path

    if out is None:
        fail("--mode camera needs -o cam.json: the camera file it writes")
    if calibration is not None:
        fail("--calibration applies to --mode pose; the camera mode calibrates the camera itself")
    output_path(out, "-o", (".json",))
    for opt, v in (("--f-target", f_target), ("--pp-target", pp_target)):
        if not (math.isfinite(v) and 0 < v <= 100):
            fail(f"{opt} must be a number > 0 and <= 100, got {v}")
    b = parse_board(board, 1.0 if square is None else square)
    live_limits(max_frames)
    # photos in room light: the board is seen wherever it is put, not only in the projector's light
    cam = _camera_opener(camera, b, exposure, gain, camera_size, virtual_pose, seed, square)((5.0, 3.0, 0.0),
                                                                                     ambient=0.8, gain=0.5)
    options = replace(AdvisorOptions(), camera_f_pct=float(f_target), camera_pp_px=float(pp_target))
    state = {"advisor": None, "last": None}

    def on_advice(img, advice):
        if json_lines:
            import sys

            sys.stdout.write(advice.to_json() + "\n")
            sys.stdout.flush()
        elif (advice.state, advice.photos) != state["last"]:
            state["last"] = (advice.state, advice.photos)
            say(f"[{advice.photos} photos, coverage {advice.coverage:.0%}] {advice.message}")

    def on_photo(advisor, name):
        fit = advisor.fit
        if not json_lines:
            say(f"took {name}" + (f": f_c = {fit.camera.K[0, 0]:.1f} px" if fit is not None else ""))

    from ._live import StdinKey

    with cam, text_on_stderr(json_lines):
        size = cam.grab().image.shape[:2][::-1]
        advisor = CameraAdvisor(b, size, options)
        res = advise_camera(cam, advisor, on_advice=on_advice, poll=StdinKey().poll, auto=auto,
                            max_frames=max_frames, on_photo=on_photo)
        if len(advisor.views) < 2:
            fail(f"stopped ({res.reason}) after {res.frames} frames with {len(advisor.views)} photo(s): a camera "
                 "calibration needs at least 2; nothing written", code=3, label="not enough")
        calib = camera_calibration(advisor, out)
        c = calib.info.get("covariance") or {}
        std = {n: float(c["matrix"][k, k]) ** 0.5 for k, n in enumerate(c.get("params", ()))}
        f = float(calib.camera.K[0, 0])
        said = (f"f_c = {f:.1f} ± {std.get('f_c', float('nan')):.2f} px, principal point ("
                f"{calib.camera.K[0, 2]:.1f}, {calib.camera.K[1, 2]:.1f}) ± {std.get('u0c', float('nan')):.1f}, "
                f"{std.get('v0c', float('nan')):.1f} px from {len(advisor.views)} photos")
        say(f"wrote {out}: {said} ({calib.verdict})")
    if res.reason != "enough":
        fail(f"stopped ({res.reason}) before the camera was determined to f_c {f_target:g} % and the principal "
             f"point {pp_target:g} px; {out} holds the {len(advisor.views)} photos' calibration: take more photos",
             code=3, label="not enough")
