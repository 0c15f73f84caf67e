"""The app's More projectors step: a rig of one camera and several projectors, one projector after another
(``procam capture --rig``), its calibration (``procam calibrate RIGPOSE``) and the blend masks of the overlapping
projectors (``procam blend RIGPOSE``), over the same library calls those commands make.

Project folder: each rig pose in ``rigN/`` (``rig.json`` and one pose folder per projector; a new capture never goes
over an earlier one), the rig's calibration in ``rig-calib.json`` with its OpenCV YAML, its drawing (the rig seen
from above with the pairs' 3-D agreement) and its HTML page, the blend masks in ``blend/`` (``alpha_<name>.png``,
``overlap_<name>.png``, ``blend.npz``).  Virtual: the simulator's two-projector rig
(:func:`procam.acquire.rig.virtual_rig`), its projectors at the app's projector size, its camera the app's
(1280x800), the board at the angles of the virtual board's pose, placed where every device sees it whole.

A step that procam knows cannot go on is refused with its reason: no rig pose yet, a rig pose whose capture did not
finish (no ``rig.json``: a cancelled or failed projector), a projector whose instant verdict is degenerate or failed
(turn the board and capture the rig again); the files are checked before the first write, so a file procam did not
write in the way stops the step with nothing written.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import ProcamError
from .jobs import Job
from .project import FILES, Project

#: The virtual rig's projectors (the simulator's rig has two).
VIRTUAL_PROJECTORS = "left,right"


def _rel(project: Project, path) -> str:
    return str(Path(path).relative_to(project.root))


def refuse_foreign(paths) -> None:
    """A one-line :class:`ProcamError` before any write when one of ``paths`` exists and procam did not write it."""
    from ..io.files import procam_wrote

    for p in paths:
        p = Path(p)
        if p.exists() and (p.is_dir() or not procam_wrote(p)):
            raise ProcamError(f"{p.name}: a file procam did not write is in the way in {p.parent}; move it away "
                              "(the app never writes over a file it did not write); nothing was written")


def projectors(devices, spec) -> tuple:
    """The rig's projectors from ``spec`` (``"left=1,right=2"``: NAME=DISPLAY, as ``procam capture --rig``; virtual:
    two names, default :data:`VIRTUAL_PROJECTORS`), checked (one line naming what is wrong)."""
    from ..acquire.rig import parse_rig_projectors

    if spec is None and devices.virtual:
        spec = VIRTUAL_PROJECTORS
    if not isinstance(spec, str) or not spec.strip():
        raise ProcamError("rig projectors: give them as NAME=DISPLAY,NAME=DISPLAY (e.g. left=1,right=2)")
    try:
        out = parse_rig_projectors(spec)
    except ValueError as e:
        raise ProcamError(f"rig projectors {spec}: {e}") from None
    if devices.virtual and len(out) != 2:
        raise ProcamError(f"rig projectors {spec}: the virtual rig has two projectors; name two")
    missing = [p.name for p in out if p.display is None]
    if missing and not devices.virtual:
        raise ProcamError(f"rig projectors {spec}: give {missing[0]}'s display (NAME=DISPLAY; the Devices step "
                          "lists the displays)")
    return out


def next_rig_name(project: Project) -> str:
    """``rigN``: the first name not in the folder."""
    n = 1
    while (project.root / f"rig{n}").exists():
        n += 1
    return f"rig{n}"


def capture(job: Job, project: Project, devices, spec=None) -> dict:
    """Capture one rig pose (:func:`procam.acquire.rig.capture_rig_pose`: each projector's whole sequence in turn,
    the board still) into the next ``rigN`` and judge each projector's pose at once; the project takes it as its rig
    pose."""
    from ..acquire.rig import capture_rig_pose, virtual_rig
    from ..acquire.session import CaptureOptions

    rig_projectors = projectors(devices, spec)
    name = next_rig_name(project)
    board = project.board()
    hooks = _RigHooks(job, project, len(rig_projectors))
    simulated = None
    if devices.virtual:
        from ..acquire.cameras import VIRTUAL_POSES

        simulated = virtual_rig([p.name for p in rig_projectors], "cam", devices.projector_size, None)
        simulated = simulated.with_board_pose(VIRTUAL_POSES[devices.pose_index])
    devices.release()
    with devices.lock:
        options = CaptureOptions(settle_s=0.0 if devices.virtual else 0.25, board=board.pattern_size)
        capture_rig_pose(project.root / name, rig_projectors, devices.capture_devices(), options, board=board,
                         hooks=hooks, simulated=simulated, announce=hooks.announce)
    verdicts = {p.name: v for p, v in zip(rig_projectors, hooks.verdicts)}
    project.state["rig"] = {"name": name, "projectors": [p.name for p in rig_projectors], "verdicts": verdicts}
    project.save()
    return {"rig": name, "verdicts": verdicts, "lines": hooks.lines, "checks": hooks.pictures}


class _RigHooks:
    """The capture session's hooks for every projector of a rig pose: progress over the whole rig, and each
    projector's instant verdict with its check picture (``rigN/<projector>.check.png``)."""

    def __init__(self, job: Job, project: Project, n: int):
        self.job, self.project, self.n = job, project, n
        self.i, self.name = 0, ""
        self.verdicts, self.lines, self.pictures = [], [], []

    def announce(self, i, n, projector):
        self.i, self.name = i, projector.name
        self.job.step(message=f"projector {i + 1}/{n}: {projector.name} -- the board and the camera stay still")

    def projector(self, projector): ...

    def camera(self, camera): ...

    def busy(self, text):
        import contextlib

        self.job.step(message=f"{self.name}: {text}")
        return contextlib.nullcontext()

    def pose(self, i, poses, kind): ...

    def place_board(self, i): ...

    def captured(self, result):
        self.job.step(message=f"{self.name}: decoding and judging the pose")

    def progress(self, i, event):
        if event.kind == "preflight" and event.data.get("ok"):  # its levels and advice head the projector's lines
            from .work import preflight_lines

            self.lines += [f"{self.name}: {line}" for line in preflight_lines(event.data)]
        done = self.i * event.total + event.index + 1 if event.kind == "frame" else None
        self.job.step(done, self.n * event.total, f"{self.name}: " + (event.message or
                      f"{event.kind} {max(event.index, 0) + 1}/{event.total}"))

    def verdict(self, result, check, png):
        from ..check import overlay
        from ..io.files import write_image

        self.verdicts.append(check.verdict)
        self.lines += [f"{self.name}: {line}" for line in check.lines]
        self.pictures.append(_rel(self.project, write_image(png, overlay(check))))

    def verdict_failed(self, result, error):
        self.verdicts.append("failed")
        self.lines.append(f"{self.name}: {error}")


def summary(project: Project) -> dict | None:
    """The page's view of the project's rig pose: its name, projectors and their verdicts, whether it was captured
    whole, each projector's check picture, the blend's alpha files; None before the first rig capture."""
    from ..capture import RIG_MANIFEST

    rig = project.state.get("rig")
    if not rig or not rig.get("name"):
        return None
    folder = project.root / rig["name"]
    names = rig.get("projectors") or []
    blend = project.file("blend")
    return {**rig, "complete": (folder / RIG_MANIFEST).is_file(),
            "checks": [f"{rig['name']}/{n}.check.png" for n in names if (folder / f"{n}.check.png").is_file()],
            "alpha": [f"{FILES['blend']}/alpha_{n}.png" for n in names if (blend / f"alpha_{n}.png").is_file()]}


def usable_rig(project: Project, *, judged: bool = True):
    """The project's rig pose (:class:`procam.capture.RigPose`) when the next step may use it: captured whole
    (``rig.json``) and, ``judged``, every projector's instant verdict good or weak."""
    from ..capture import RIG_MANIFEST, read_rig_pose

    rig = project.state.get("rig") or {}
    if not rig.get("name"):
        raise ProcamError("no rig pose yet: capture one in the More projectors step")
    folder = project.root / rig["name"]
    if not (folder / RIG_MANIFEST).is_file():
        raise ProcamError(f"the rig pose {rig['name']} was not captured whole (no {RIG_MANIFEST}); capture the rig "
                          "again")
    bad = {p: v for p, v in (rig.get("verdicts") or {}).items() if v not in ("good", "weak")}
    if judged and bad:
        p, v = next(iter(bad.items()))
        raise ProcamError(f"the rig pose {rig['name']}: projector {p} is {v}; turn the board as its verdict says "
                          "and capture the rig again")
    return read_rig_pose(folder)


def calibrate(job: Job, project: Project) -> dict:
    """Calibrate the rig pose (``procam calibrate RIGPOSE``: each pair single-pose with the shared camera, the pairs'
    agreement in 3-D); a rig calibration procam can trust is written with its YAML, drawing and page."""
    from ..rig import calibrate_rig, rig_views_from_folders
    from ..rig.verify import verify_rig

    pose = usable_rig(project)
    outs = [project.file(k) for k in ("rig_calibration", "rig_yaml", "rig_figure", "rig_report")]
    refuse_foreign(outs)
    total = len(pose.pairs) + 2
    views = rig_views_from_folders([pose.folder], project.board(),
                                   progress=lambda done, n, f: job.step(done, total, f"decoded {_rel(project, f)}"))
    job.step(len(pose.pairs), total, "calibrating the rig")
    rc = calibrate_rig(views)
    agreement = verify_rig(rc, views)
    result = describe(rc, agreement)
    result["written"] = []
    if rc.trusted:
        job.step(total - 1, total, "writing the rig's calibration, its drawing and page")
        result["written"] = _write(project, rc, agreement, outs)
    project.state["rig_calibration"] = {"verdict": rc.verdict, "trusted": bool(rc.trusted)}
    project.save()
    return result


def _write(project: Project, rc, agreement, outs) -> list[str]:
    """What ``procam calibrate RIGPOSE -o rig-calib.json --yaml rig-calib.yml --png ... --report ...`` writes."""
    from ..io.rig import check_rig_yaml, save_rig_calibration
    from ..plots import save_figure
    from ..report import build_rig_report, write_report
    from ..rig.draw import rig_figure

    out, yaml, png, page = outs
    check_rig_yaml(rc, yaml)
    save_rig_calibration(rc, out)
    save_rig_calibration(rc, yaml)
    save_figure(rig_figure(rc, agreement, title=out.name), png)
    write_report(build_rig_report(rc, None, agreement=agreement, name=out.name), page)
    return [_rel(project, p) for p in outs]


def describe(rc, agreement) -> dict:
    """The page's view of a rig calibration: its device, relative-pose and agreement tables (the cells ``procam
    calibrate`` prints), each device's f with its 1-sigma std and verdict, the rig's verdict with its reasons."""
    from ..rig.tables import agreement_table, device_table, relative_table
    from ..verdict import MEANING

    def table(t):
        return {"header": list(t.header), "rows": [list(map(str, r)) for r in t.rows]}

    return {"method": rc.method, "verdict": rc.verdict, "meaning": MEANING.get(rc.verdict, ""),
            "reasons": list(rc.verdict_reasons), "trusted": bool(rc.trusted), "uncertainty": rc.uncertainty,
            "devices": {d.name: {"kind": d.kind, "f": float(d.device.K[0, 0]), "f_std": d.std.get("f"),
                                 "verdict": d.verdict} for d in rc.devices},
            "device_table": table(device_table(rc)), "relative_table": table(relative_table(rc)),
            "agreement_table": table(agreement_table(agreement))}


def blend(job: Job, project: Project, grid: int = 8) -> dict:
    """The blend masks of the rig pose's projectors (``procam blend RIGPOSE -o blend``): per projector, alpha per
    projector pixel, summing to 1 where the projectors overlap on what the camera sees."""
    from .. import capture, decode
    from ..rig.blend import blend_masks, write_blend

    pose = usable_rig(project, judged=False)
    pairs = [p for p in pose.pairs if p.camera == pose.reference]
    if len(pairs) < 2:
        raise ProcamError(f"{pose.folder.name}: the camera sees {len(pairs)} projector(s); blending needs two or more")
    folder = project.file("blend")
    refuse_foreign([folder / f"{k}_{p.projector}.png" for p in pairs for k in ("alpha", "overlap")] +
                   [folder / "blend.npz"])
    maps, sizes = {}, {}
    for k, p in enumerate(pairs):
        job.step(k, len(pairs) + 1, f"decoding {p.projector}")
        cap = capture.load_capture(p.folder)
        d = decode.decode(cap.stack, cap.pattern_set, extras=False)
        maps[p.projector] = (d.col, d.row)
        sizes[p.projector] = (cap.pattern_set.width, cap.pattern_set.height)
    job.step(len(pairs), len(pairs) + 1, "blending")
    b = blend_masks(maps, sizes, grid=grid)
    written = write_blend(b, folder)
    return {"written": [_rel(project, p) for p in written],
            "overlap": {n: float(b.overlap[n].mean()) for n in b.alpha},
            "seen": {n: float(b.seen[n].mean()) for n in b.alpha},
            "alpha": {n: f"{FILES['blend']}/alpha_{n}.png" for n in b.alpha}}
