"""What each step of the app does, over the library (the calls ``procam capture``, ``calibrate``, ``world-check`` and
``export`` make), reading and writing the project folder (:mod:`procam.app.project`).  Every function returns a
JSON-ready dict for the page; long ones take the :class:`~procam.app.jobs.Job` they run in.  Nothing here decides
anything about a calibration: the verdicts are the library's.
"""

from __future__ import annotations

import json
import math
import re
import threading
from contextlib import ExitStack
from pathlib import Path

from ..errors import ProcamError
from .jobs import Job
from .project import FILES, Project

#: A camera step is "enough" when the camera's focal length is known to this fraction (1 sigma).
CAMERA_ENOUGH = 0.005


def _rel(project: Project, path) -> str:
    return str(Path(path).relative_to(project.root))


def board_svg(project: Project) -> dict:
    """Write the printable board (:func:`procam.board.printable_svg`) into the project folder."""
    from ..board import printable_svg
    from ..io.files import write_text
    from ..io.formats import SOFTWARE

    path = write_text(project.file("board"), printable_svg(project.board(), project.state["unit"], SOFTWARE))
    return {"file": _rel(project, path)}


# ---------------------------------------------------------------------------------------------------------------
# the camera's live view with the advisor's advice
# ---------------------------------------------------------------------------------------------------------------
class Advising:
    """The advisor (:class:`procam.advisor.Advisor`) of the live view, made again when the board, the image size or
    the camera file changes; it knows the camera file's intrinsics and, once calibrated, the projector side."""

    def __init__(self):
        self.advisor = None
        self.key = None

    def advice(self, project: Project, image):
        from ..advisor import Advisor

        board = project.board()
        key = (board, image.shape, project.state.get("camera_file"))
        if self.key != key:
            self.advisor = Advisor(board, (image.shape[1], image.shape[0]))
            self.key = key
            camera_file = project.state.get("camera_file")
            calib = saved_calibration(project)
            if calib is not None and calib.projector is not None and tuple(calib.camera.image_size) == \
                    self.advisor.image_size:
                self.advisor.set_calibration(calib, FILES["calibration"])
            elif camera_file:
                from ..io import load_camera_intrinsics

                self.advisor.set_camera(load_camera_intrinsics(project.path(camera_file), self.advisor.image_size),
                                        camera_file)
        return self.advisor.update(image)

    def learn(self, calib, source: str) -> None:
        """Advise from ``calib`` (its intrinsics and R, T) from now on."""
        if self.advisor is not None:
            self.advisor.set_calibration(calib, source)


class LiveView:
    """The camera's live view: each request gets the newest frame at once, and the advice of the newest frame the
    advisor has finished; the advisor works in a thread of its own, and as soon as it is done with a frame it takes
    the newest frame served since, so neither waits for the other (the frame rate is the camera's, the advice's rate
    the advisor's)."""

    def __init__(self):
        self.advising = Advising()
        self.frame = 0
        self.latest: dict | None = None
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()
        self._pending = None  # (project, image, frame) the advisor takes next

    def _advisor(self) -> None:
        while True:
            with self._lock:
                job, self._pending = self._pending, None
                if job is None:
                    self._thread = None
                    return
            self._advise(*job)

    def _advise(self, project: Project, image, frame: int) -> None:
        from ..acquire.preview import advice_lines  # the preview window's text panel, word for word
        from .jobs import error_line, results_carry_warnings

        try:
            with results_carry_warnings():
                advice = self.advising.advice(project, image)
            lines = [{"style": style, "text": text} for style, text in advice_lines(advice)]
            self.latest = {**advice.to_dict(corners=True), "lines": lines, "of_frame": frame}
        except Exception as e:  # noqa: BLE001 - the page shows why there is no advice
            self.latest = {"error": error_line(e), "of_frame": frame}

    def preview(self, project: Project, devices) -> tuple[bytes, int, dict | None]:
        """(JPEG bytes of a new 8-bit camera frame, its number, the newest advice or None): the advice (a
        :meth:`procam.advisor.Advice.to_dict` with its corners, ``lines`` the text panel of ``procam advise``'s window
        and ``of_frame``, the frame it was made from) is of this frame or an earlier one."""
        import cv2
        import numpy as np

        image = devices.grab()
        with self._lock:
            self.frame += 1
            frame = self.frame
            self._pending = (project, image, frame)
            if self._thread is None:  # ends when no frame waits: the interpreter may wait for it
                self._thread = threading.Thread(target=self._advisor, name="procam-app-advice")
                self._thread.start()
        shown = image if image.dtype == np.uint8 else (image >> 8).astype(np.uint8)
        ok, buf = cv2.imencode(".jpg", shown, [cv2.IMWRITE_JPEG_QUALITY, 80])
        if not ok:
            raise ProcamError("the camera frame could not be encoded as JPEG")
        return buf.tobytes(), frame, self.latest

    def wait(self, timeout: float | None = None) -> dict | None:
        """The advice once the advisor is done with every frame served (tests, scripts)."""
        thread = self._thread
        if thread is not None:
            thread.join(timeout)
        return self.latest


# ---------------------------------------------------------------------------------------------------------------
# Camera: photos of the board (camera-only calibration) or a camera file
# ---------------------------------------------------------------------------------------------------------------
def photos(project: Project) -> list[Path]:
    folder = project.file("photos")
    return sorted(folder.glob("photo[0-9][0-9].png")) if folder.is_dir() else []


def take_photo(project: Project, devices, job: Job | None = None) -> dict:
    """Grab a photo of the board into ``camera/photoNN.png`` (refused when the board is not found in it), then
    calibrate the camera from all photos so far (:func:`camera_from_photos`)."""
    from ..board import corners as _corners
    from ..io.files import write_image

    if job is not None:
        job.step(0, 2, "taking the photo")
    image = devices.grab()
    found, _ = _corners.find_corners([image], project.board().pattern_size)
    if found is None:
        raise ProcamError("the board is not in view (or not all of it): bring the whole board into the camera's "
                          "image, then take the photo")
    n = len(photos(project)) + 1
    write_image(project.file("photos") / f"photo{n:02d}.png", image)
    if job is not None:
        job.step(1, 2, f"calibrating the camera from {n} photo(s)")
    return camera_from_photos(project)


def camera_from_photos(project: Project) -> dict:
    """The camera calibrated from the photos (``procam calibrate --camera-only``), written to ``camera.json``
    and used by the next steps when it can be trusted; its focal length's ± and whether that is enough."""
    import numpy as np

    from .. import io, method, pipeline

    files = photos(project)
    if not files:
        raise ProcamError("no photos yet: take a photo of the board first")
    board = project.board()
    views = [pipeline.camera_only_view(p, board) for p in files]
    calib = method.calibrate(views, method="camera-only")
    f, sf = float(calib.camera.K[0, 0]), calib.std.get("f_c")
    sf = float(sf) if sf is not None and math.isfinite(sf) else None
    from ..board import board_outline
    from ..report.coverage import coverage_fractions

    covered = coverage_fractions(views, views[0].cam_size)["camera"]
    project.state["photos"] = {"outlines": [np.round(board_outline(v.cam_pts), 1).tolist() for v in views],
                               "coverage": covered}
    out = {"photos": [_rel(project, p) for p in files], "verdict": calib.verdict,
           "reasons": list(calib.verdict_reasons), "f": f, "f_std": sf, "coverage": covered,
           "enough": bool(calib.trusted and sf is not None and sf <= CAMERA_ENOUGH * f)}
    if calib.trusted:
        io.save_calibration(calib, project.file("camera"))
        project.state["camera_file"] = FILES["camera"]
        out["file"] = FILES["camera"]
    project.save()
    return out


def use_camera_file(project: Project, name: str | None) -> dict:
    """Use the camera file ``name`` (inside the project folder; procam JSON or OpenCV YAML/XML) for the next
    steps, or none (``name`` None: the single-pose method calibrates the camera too)."""
    if name:
        from ..io import load_camera_intrinsics

        path = project.path(name)
        if not path.is_file():
            raise ProcamError(f"{name}: no such file in the project folder; copy the camera file there first")
        dev = load_camera_intrinsics(path)
        name = _rel(project, path)
        desc = {"f": float(dev.K[0, 0]), "size": list(dev.image_size) if dev.image_size is not None else None}
    else:
        desc = {}
    project.state["camera_file"] = name or None
    project.save()
    return {"camera_file": name or None, **desc}


# ---------------------------------------------------------------------------------------------------------------
# Projector pose: capture, decode, verdict
# ---------------------------------------------------------------------------------------------------------------
def next_pose_name(project: Project) -> str:
    """``poseN``: the first name not in the folder (a new capture never goes over an earlier one)."""
    n = 1
    while (project.root / f"pose{n}").exists():
        n += 1
    return f"pose{n}"


class _Hooks:
    """The capture session's hooks (:class:`procam.acquire.orchestrate.Hooks`) for a job: progress, and the
    pose's instant verdict with its picture."""

    def __init__(self, job: Job, project: Project):
        self.job, self.project = job, project
        self.check, self.error, self.png, self.preflight = None, None, None, None

    def projector(self, projector): ...

    def camera(self, camera): ...

    def busy(self, text):
        self.job.step(message=text)
        import contextlib

        return contextlib.nullcontext()

    def pose(self, i, poses, kind): ...

    def place_board(self, i): ...

    def progress(self, i, event):
        if event.kind == "preflight":
            self.preflight = event.data
        self.job.step(event.index + 1 if event.kind == "frame" else None, event.total,
                      event.message or f"{event.kind} {max(event.index, 0) + 1}/{event.total}")

    def captured(self, result):
        self.job.step(message="decoding and judging the pose")

    def verdict(self, result, check, png):
        from ..check import overlay
        from ..io.files import write_image

        self.check, self.png = check, write_image(png, overlay(check))

    def verdict_failed(self, result, error):
        self.error = str(error)


def capture(job: Job, project: Project, devices, advising: Advising | None = None) -> dict:
    """Capture a pose (``procam capture``: pre-flight, the sequence, post-flight) into the next ``poseN`` and judge
    it at once; the project takes it as its pose, and ``advising`` learns the projector side from the pose's
    quick calibration (as ``procam capture --advise`` does between poses)."""
    from ..acquire.orchestrate import capture_session
    from ..acquire.session import CaptureOptions

    name = next_pose_name(project)
    board = project.board()
    hooks = _Hooks(job, project)
    devices.release()
    with devices.lock:
        options = CaptureOptions(settle_s=0.0 if devices.virtual else 0.25, board=board.pattern_size)
        capture_session(project.root / name, 1, devices.capture_devices(), options, board=board, hooks=hooks)
    check = hooks.check
    verdict = check.verdict if check is not None else "failed"
    if advising is not None and check is not None and check.calibration is not None and verdict in ("good", "weak"):
        advising.learn(check.calibration, name)
    project.state["pose"] = {"name": name, "verdict": verdict}
    project.save()
    pre = hooks.preflight or {}
    preflight = preflight_lines(pre) if pre.get("ok") else []
    return {"pose": name, "verdict": verdict, "lines": preflight + (list(check.lines) if check else [hooks.error]),
            "reasons": list(check.reasons) if check else [hooks.error],
            "check": _rel(project, hooks.png) if hooks.png else None, "preflight": hooks.preflight}


def preflight_lines(pre: dict) -> list[str]:
    """The pre-flight's levels and suggestions in words (as ``procam capture`` prints them); a refused one's reason."""
    if not pre.get("ok"):
        return [f"pre-flight: {pre.get('reason')}"]
    return [(f"pre-flight: white {pre['white_level']:.0%} of full scale on the {pre['region']} "
             f"({pre['white_saturated']:.1%} saturated), black {pre['dark_level']:.0%}, contrast "
             f"{pre['contrast']:.0%}"), *pre.get("suggestions", [])]


def exposure_check(job: Job, project: Project, devices) -> dict:
    """The capture's pre-flight alone (:func:`procam.acquire.session.preflight_check`), before a capture: the
    projector shows white, black and white again, the camera's levels on the board are judged, and the
    suggestions say what to change (exposure, gain, the room's light); ``ok`` False: the capture would refuse."""
    from ..acquire.session import CaptureOptions, preflight_check

    board = project.board()
    size = devices.projector_size if devices.virtual else devices.describe()["projector_size"]
    if size is None:
        raise ProcamError(f"no projector to light the board: {devices.describe()['projector']}")
    job.step(0, 1, "white, black and white again on the projector")
    devices.release()
    with ExitStack() as stack, devices.lock:
        show_and_grab = devices.lit_grab(stack, size)
        pre, record = preflight_check(lambda image: (show_and_grab(image), 1), size,
                                      CaptureOptions(board=board.pattern_size))
    job.step(1, 1, "judged")
    return {"ok": bool(pre.ok), "reason": pre.reason, "lines": preflight_lines(record), "levels": record}


# ---------------------------------------------------------------------------------------------------------------
# Calibrate
# ---------------------------------------------------------------------------------------------------------------
def usable_pose(project: Project) -> str:
    """The project's pose folder, when its instant verdict lets it be calibrated."""
    pose = project.state.get("pose") or {}
    if not pose.get("name") or not (project.root / pose["name"] / "capture.json").is_file():
        raise ProcamError("no projector pose yet: capture one in the Projector pose step")
    if pose.get("verdict") not in ("good", "weak"):
        raise ProcamError(f"the pose {pose['name']} is {pose.get('verdict')}: turn the board as its verdict says "
                          "and capture again")
    return pose["name"]


def calibrate(job: Job, project: Project) -> dict:
    """Calibrate the pose (``procam calibrate POSE [--camera FILE]``): the numbers with their ±, the verdict,
    the metric verification; a trusted calibration is written (JSON, YAML, the residual figure, the report)."""
    from .. import io, method, pipeline
    from ..verdict import with_evidence
    from ..verify import verify_calibration

    name = usable_pose(project)
    board = project.board()
    job.step(0, 4, f"decoding {name}")
    views = pipeline.views_from_folders([project.root / name], board)
    known = None
    if project.state.get("camera_file"):
        known = io.load_camera_intrinsics(project.path(project.state["camera_file"]), views[0].cam_size)
    job.step(1, 4, "calibrating")
    calib = method.calibrate(views, known_camera=known)
    job.step(2, 4, "verifying")
    check = verify_calibration(calib)
    calib = with_evidence(calib, check)
    result = describe_calibration(calib)
    result["written"] = []
    if calib.trusted:
        job.step(3, 4, "writing the calibration, its figure and report")
        result["written"] = write_calibration(project, calib, check)
    project.state["calibration"] = {"verdict": calib.verdict, "trusted": bool(calib.trusted)}
    project.save()
    return result


def describe_calibration(calib) -> dict:
    """The page's view of a calibration: its parameter table with the ±, what the projector's numbers rest on,
    the verdict in words with its reasons."""
    from .. import summary
    from ..verdict import MEANING

    table = summary.parameter_table(calib)
    f_p = float(calib.projector.K[0, 0]) if calib.projector is not None else None
    return {"method": calib.method, "plus_minus": summary.plus_minus(calib), "header": list(table.header),
            "rows": [list(map(str, r)) for r in table.rows], "rests_on": summary.projector_assumptions(calib),
            "verdict": calib.verdict, "meaning": MEANING.get(calib.verdict, ""), "reasons": list(calib.verdict_reasons),
            "warnings": list(calib.warnings), "trusted": bool(calib.trusted), "f_p": f_p,
            "f_c": float(calib.camera.K[0, 0])}


def write_calibration(project: Project, calib, check) -> list[str]:
    """Write what ``procam calibrate -o calib.json --yaml calib.yml --png ... --report calib.html`` writes."""
    from .. import io
    from ..plots import save_figure
    from ..plots.residuals import residual_figure
    from ..report import build_report, write_report
    from ..residuals import calibration_residuals
    from ..verdict import calibration_verdict

    io.save_calibration(calib, project.file("calibration"))
    io.save_opencv_yaml(calib, project.file("yaml"))
    fig = residual_figure(calibration_residuals(calib), calib.camera.image_size, calib.projector.image_size,
                          title=f"{FILES['calibration']}: {calib.method}", verdict=calibration_verdict(calib).line())
    save_figure(fig, project.file("residuals"))
    write_report(build_report(calib, check=check, name=FILES["calibration"]), project.file("report"))
    return [FILES[k] for k in ("calibration", "yaml", "residuals", "report")]


def saved_calibration(project: Project):
    """The project's calibration file, read (None when there is none)."""
    from .. import io

    f = project.file("calibration")
    return io.load_calibration(f) if f.is_file() else None


def need_calibration(project: Project):
    """The project's calibration, when the next steps may use it (a one-line :class:`ProcamError` says why not)."""
    latest = project.state.get("calibration") or {}
    if latest and not latest.get("trusted"):
        raise ProcamError(f"the latest calibration is {latest.get('verdict')} and was not written; capture a better "
                          "pose and calibrate again (an earlier calibration file is not used in its place)")
    calib = saved_calibration(project)
    if calib is None:
        raise ProcamError(f"no calibration in the project yet ({FILES['calibration']}): calibrate first")
    if calib.projector is None or calib.R is None:
        raise ProcamError(f"{FILES['calibration']}: a camera-only calibration; calibrate a projector pose first")
    return calib


# ---------------------------------------------------------------------------------------------------------------
# Check in the world, Export
# ---------------------------------------------------------------------------------------------------------------
def check_world(job: Job, project: Project, devices) -> dict:
    """Project spots where the calibration says the board's white squares are and measure where they land
    (``procam world-check``); the picture and the numbers go into the project folder."""
    from ..io.files import write_image, write_text
    from ..world_check import draw, world_check

    calib = need_calibration(project)
    job.step(0, 2, "projecting the spots and finding them")
    with ExitStack() as stack, devices.lock:
        show_and_grab = devices.show_and_grab(stack, calib.projector.image_size)
        wc = world_check(calib, project.board(), show_and_grab)
    job.step(1, 2, "drawing")
    write_image(project.file("world"), draw(wc))
    write_text(project.file("world_json"), json.dumps(wc.to_dict(), indent=1))
    found = sum(s == "found" for s in wc.status)
    return {"verdict": wc.verdict, "reasons": list(wc.reasons), "diagnosis": wc.diagnosis,
            "rms_px": float(wc.rms_px), "max_px": float(wc.max_px), "rms": float(wc.rms), "found": int(found),
            "targets": len(wc.status), "picture": FILES["world"], "numbers": FILES["world_json"]}


#: The exports the app writes: name -> (file in export/, what it is).
EXPORTS = {"blender": ("blender.json", "Blender cameras (+ the script that makes them)"),
           "unity": ("unity.json", "Unity cameras"),
           "opengl": ("opengl.json", "OpenGL / TouchDesigner projection and view matrices"),
           "yaml": ("calib.yml", "OpenCV YAML (cam_K, cam_kc, proj_K, proj_kc, R, T)")}


def export_checked(project: Project, formats, near, far):
    """The calibration to export, after checking the request (one line naming the wrong field)."""
    calib = need_calibration(project)
    if not isinstance(formats, list) or not formats or any(f not in EXPORTS for f in formats):
        raise ProcamError(f"export formats: give a list of some of {', '.join(EXPORTS)}, got {formats!r}")
    for name, v in (("near", near), ("far", far)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ProcamError(f"export {name}: give a clipping distance in the board's unit, got {v!r}")
    from ..export.frames import check_clip

    try:
        check_clip(near, far)
    except ProcamError as e:
        raise ProcamError(f"export near/far: {e}") from None
    return calib


def export(project: Project, formats, near: float, far: float, job: Job | None = None) -> dict:
    """Write the calibration for the next tools into ``export/`` (``procam export --format F``); ``near``,
    ``far`` the clipping distances in the board's unit."""
    from .. import export as ex
    from .. import io
    from ..export.frames import metres_per_unit
    from ..export.maps import distortion_maps
    from ..io.engines import save_distortion_maps

    calib = export_checked(project, formats, near, far)
    unit = project.state["unit"]
    folder = project.file("export")
    written = []
    for k, fmt in enumerate(formats):
        if job is not None:
            job.step(k, len(formats), f"writing {EXPORTS[fmt][0]}")
        out = folder / EXPORTS[fmt][0]
        if fmt == "yaml":
            written.append(io.save_opencv_yaml(calib, out))
            continue
        if fmt == "opengl":
            doc = ex.opengl_document(calib, near, far)
        else:
            make = ex.blender_document if fmt == "blender" else ex.unity_document
            m = metres_per_unit(unit)
            doc = make(calib, unit=unit, near_m=near * m, far_m=far * m)
        doc["calibration"] = "../" + FILES["calibration"]
        doc["distortion_maps"] = save_distortion_maps(out, distortion_maps(calib))
        written += (io.engines.save_blender(doc, out, ex.blender.script_text()) if fmt == "blender"
                    else [io.engines.save_document(doc, out)])
        written += [folder / m[k] for m in doc["distortion_maps"].values() for k in ("remap", "st_map")]
    return {"written": sorted({_rel(project, p) for p in written})}


def safe_name(name: str) -> bool:
    """A file name the page may ask for (letters, digits, ``._-/``, no ``..``)."""
    return bool(re.fullmatch(r"[\w./-]{1,200}", name)) and ".." not in name.split("/")
