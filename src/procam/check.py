"""Is this pose's capture good? The instant verdict on one pose folder, in seconds, without writing a
calibration: capture checks -> decode -> corners -> single-pose calibration -> verdict, and one overlay picture
(the white frame with the decoded area, the corners and the verdict).

Used by ``procam check POSE_DIR`` and by ``procam capture`` right after each pose, so the user learns whether
the pose was good before leaving the rig.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import capture, pipeline, single_pose, summary
from .board import Board
from .errors import CalibrationError, DegeneratePoseError, ProcamWarning
from .style import NEUTRAL, VERDICT_COLOURS, bgr


@dataclass(frozen=True)
class PoseCheck:
    """The instant verdict of one pose.

    Attributes
    ----------
    folder : the pose folder.
    verdict : ``good``, ``weak``, ``degenerate`` or ``failed`` (:mod:`procam.single_pose.rating`).
    reasons : the verdict's reasons, one line each.
    lines : what to print, one line each (corners, decoded area, angles, focal lengths with their ±, verdict).
    view : the pose's :class:`~procam.view.View`; maps : its :class:`~procam.decode.DecodeResult`.
    calibration : the single-pose :class:`~procam.calibration.Calibration`, or None when no solution exists.
    white : (H, W) the white frame, for the overlay.
    seconds : how long the check took.
    """

    folder: Path
    verdict: str
    reasons: tuple
    lines: tuple
    view: object
    maps: object
    calibration: object
    white: np.ndarray
    seconds: float


def check_pose(folder, board: Board, projector=None, order=None, *, options: pipeline.PoseOptions = pipeline.PoseOptions(),
               step=None, background: str = "free") -> PoseCheck:
    """The instant verdict of the pose captured in ``folder`` (see the module docstring).

    Raises the capture's own errors (:class:`~procam.errors.CaptureError`, ``BoardNotFoundError``, ...) when the
    pose cannot be used at all; a pose that decodes but calibrates badly returns its verdict.
    """
    t0 = time.perf_counter()
    folder = Path(folder)
    cap = capture.load_capture(folder, projector, order, step=step)
    view, maps = pipeline.view_from_stack(cap.stack, cap.pattern_set, board, name=str(folder), options=options,
                                          warnings=cap.warnings, files=cap.files)
    lines = [f"{int(view.valid.sum())} of {len(view.valid)} corners with projector coordinates; "
             f"{maps.valid.mean():.0%} of the camera image decoded"]
    lines += [f"warning: {w}" for w in view.diagnostics.get("warnings", [])]
    calib = None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        try:
            calib = single_pose.calibrate(view, background=single_pose.background.BackgroundOptions(mode=background))
        except DegeneratePoseError as e:
            verdict, reasons = "degenerate", (str(e),)
        except CalibrationError as e:
            verdict, reasons = "failed", (str(e),)
    if calib is not None:
        verdict, reasons = calib.verdict, calib.verdict_reasons
        p = calib.poses[0]
        ca, pa = p["camera_angles_deg"], p["projector_angles_deg"]
        lines.append(f"board angles: camera psi {ca[0]:.1f}, nu {ca[1]:.1f} deg; projector psi {pa[0]:.1f}, "
                     f"nu {pa[1]:.1f} deg")
        lines.append(f"f_c = {calib.camera.K[0, 0]:.1f} ± {calib.std.get('f_c', float('nan')):.2g} px, "
                     f"f_p = {calib.projector.K[0, 0]:.1f} ± {calib.std.get('f_p', float('nan')):.2g} px "
                     f"(± from the fit; {_projector_model(calib)})")
    for r in reasons:
        lines.append(r)
    lines.append(f"verdict: {verdict}" + {"good": " -- keep this pose", "weak": " -- usable; a better pose would be "
                                          "more precise", "degenerate": " -- capture another pose as advised",
                                          "failed": " -- capture another pose as advised"}.get(verdict, ""))
    return PoseCheck(folder, verdict, tuple(reasons), tuple(lines), view, maps, calib, cap.white,
                     time.perf_counter() - t0)


def _projector_model(calib) -> str:
    """What the projector's numbers assume: the paper's u0p = W/2, alpha_p = 1, or what the background freed."""
    return "single-pose model: " + "; ".join(summary.projector_assumptions(calib)[:2])




def overlay(check: PoseCheck, max_width: int = 1280) -> np.ndarray:
    """(H, W, 3) uint8 BGR picture: the white frame, the decoded area tinted, every corner (green with projector
    coordinates, red without) and the verdict written across the top."""
    import cv2

    from .io.files import full_scale_of

    w = check.white.astype(np.float32) * (255.0 / full_scale_of(check.white))
    img = np.repeat(np.clip(w, 0, 255).astype(np.uint8)[..., None], 3, axis=2)
    tint = np.zeros_like(img)
    tint[check.maps.valid] = (255, 160, 0)
    img = cv2.addWeighted(img, 1.0, tint, 0.35, 0)
    for (x, y), ok in zip(check.view.cam_pts, check.view.valid):
        if np.isfinite(x) and np.isfinite(y):
            cv2.circle(img, (int(round(x)), int(round(y))), 5, (60, 200, 60) if ok else (40, 40, 230), 2,
                       cv2.LINE_AA)
    scale = min(1.0, max_width / img.shape[1])
    if scale < 1.0:
        img = cv2.resize(img, (int(img.shape[1] * scale), int(img.shape[0] * scale)), interpolation=cv2.INTER_AREA)
    colour = bgr(VERDICT_COLOURS.get(check.verdict, NEUTRAL))
    text = overlay_lines(check, img.shape[1] - 20)
    h = 28 * len(text) + 12
    cv2.rectangle(img, (0, 0), (img.shape[1], h), (30, 30, 30), -1)
    for k, t in enumerate(text):
        cv2.putText(img, t, (10, 26 + 28 * k), cv2.FONT_HERSHEY_SIMPLEX, 0.7 if k == 0 else 0.5,
                    colour if k == 0 else (230, 230, 230), 2 if k == 0 else 1, cv2.LINE_AA)
    return img


def overlay_lines(check: PoseCheck, width_px: int, max_lines: int = 8) -> list[str]:
    """The text lines of :func:`overlay`: the verdict, then up to three reasons wrapped at word boundaries to
    ``width_px`` pixels of the picture's font (a word is never cut); an ellipsis ends the last line when the
    reasons need more than ``max_lines`` lines."""
    import cv2

    def fits(t):
        return cv2.getTextSize(t, cv2.FONT_HERSHEY_SIMPLEX, 0.5, 1)[0][0] <= width_px

    lines = [f"verdict: {check.verdict}"]
    for reason in check.reasons[:3]:
        line = ""
        for word in reason.split(": ", 1)[-1].split():
            if line and not fits(f"{line} {word}"):
                lines.append(line)
                line = word
            else:
                line = f"{line} {word}" if line else word
        if line:
            lines.append(line)
    if len(lines) > max_lines:
        lines = lines[:max_lines]
        lines[-1] += " ..."
    return lines
