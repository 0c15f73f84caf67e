"""``procam calibrate``: single-pose (one folder), multi-pose (several) or camera-only (photos); the method is
:func:`procam.method.choose`'s."""

from __future__ import annotations

from pathlib import Path

import typer

from .. import choices
from ._app import app, console, fail, given, keep_freed_memory, say, user_errors, warn
from ._options import (
    BackgroundOpt,
    BoardOpt,
    OrderOpt,
    ProjectorOpt,
    SquareOpt,
    StepOpt,
    choice,
    number,
    optional_size,
    parse_board,
    pose_options,
    value,
    with_pose_options,
)
from ._paths import FIGURE_SUFFIXES, distinct_poses, output_path

Cod = choice("Cod", choices.COD_MODES)
DistModel = choice("DistModel", choices.DIST_CHOICES)
Method = choice("Method", ("single", "multi"))
#: The library's name of each --method.
_METHODS = {"single": "single-pose", "multi": "multi-pose", None: None}


def _tolerance(text: str, option: str, default: float) -> tuple[str, float]:
    """``"VALUE+-TOL"`` (or ``±``) -> (``"VALUE"``, TOL); no tolerance given -> ``default``."""
    for sep in ("+-", "±", "+/-"):
        if sep in text:
            head, tol = text.split(sep, 1)
            return head, number(_float(tol, option), option, lo=0, lo_open=True, hi=1e6, what="a tolerance")
    return text, default


def _float(text: str, option: str) -> float:
    try:
        return float(text)
    except ValueError:
        fail(f"{option}: {text!r} is not a number")


def _dense_options(throw_ratio, lens_shift, projector_file):
    """The single-pose projector's options from ``--throw-ratio``, ``--lens-shift`` (priors) and
    ``--projector-intrinsics`` (checked here, before any work; :func:`_refuse_unused` has refused them where they do
    not apply)."""
    from ..single_pose.dense import DenseOptions, ProjectorPrior

    if projector_file is not None and (throw_ratio or lens_shift):
        fail("--projector-intrinsics gives the projector's intrinsics; --throw-ratio and --lens-shift are priors for "
             "estimating them: use one or the other")
    if not (throw_ratio or lens_shift):
        return DenseOptions()
    kw = {}
    if throw_ratio:
        head, tol = _tolerance(throw_ratio, "--throw-ratio", 0.02)
        kw["throw_ratio"] = number(_float(head, "--throw-ratio"), "--throw-ratio", lo=0.05, hi=20,
                                   what="a throw ratio")
        kw["throw_ratio_std"] = number(tol, "--throw-ratio tolerance", lo=0, lo_open=True, hi=5)
    if lens_shift:
        head, tol = _tolerance(lens_shift, "--lens-shift", 2.0)
        parts = head.replace(" ", "").split(",")
        if len(parts) != 2:
            fail(f"--lens-shift must be H,V in percent (e.g. 0,50), got {lens_shift!r}")
        kw["shift_h_pct"], kw["shift_v_pct"] = (number(_float(v, "--lens-shift"), "--lens-shift", lo=-300, hi=300,
                                                       what="a lens shift in percent") for v in parts)
        kw["shift_std_pct"] = number(tol, "--lens-shift tolerance", lo=0, lo_open=True, hi=100)
    return DenseOptions(prior=ProjectorPrior(**kw))


#: What each option that applies to some calibrations only is, and the calibrations (:func:`_path`) it applies to.
_APPLIES = {
    "--camera": ("the camera's intrinsics, fixed for a single-pose calibration", {"single-pose"}),
    "--projector-intrinsics": ("the projector's intrinsics, fixed for a single-pose calibration", {"single-pose"}),
    "--throw-ratio": ("a datasheet prior of the single-pose projector fit", {"single-pose"}),
    "--lens-shift": ("a datasheet prior of the single-pose projector fit", {"single-pose"}),
    "--cod": ("how a single-pose fit finds the camera's principal point",
              {"single-pose", "camera-only (one photo)", "rig single-pose"}),
    "--background": ("the scene behind the board in the single-pose projector fit", {"single-pose", "rig single-pose"}),
    "--cam-dist": ("the camera distortion model of a calibration from several poses",
                   {"multi-pose", "camera-only (several photos)", "rig multi-pose"}),
    "--proj-dist": ("the projector distortion model of a multi-pose calibration", {"multi-pose", "rig multi-pose"}),
    "--no-refine": ("skips a multi-pose calibration's joint refinement", {"multi-pose", "rig multi-pose"}),
    "--strict": ("how a multi-pose calibration treats a pose whose board is not found", {"multi-pose"}),
}
#: The calibrations of a projector and a camera from pattern captures (not camera-only): what reads pose folders.
_PAIRS = {"single-pose", "multi-pose", "rig single-pose", "rig multi-pose"}
#: The options that read pose folders' pattern captures, which a camera-only calibration (photos) has none of.
_APPLIES.update({flag: ("how the pattern captures of a projector-camera calibration are read or calibrated", _PAIRS)
                 for flag in ("--method", "--projector", "--order", "--step", "--decode", "--shadow-threshold",
                              "--contrast-threshold", "--window", "--estimator")})
#: The parameters of the options in :data:`_APPLIES` (:func:`procam.cli._app.given` names each by its flag).
_APPLIES_PARAMS = ("camera_file", "projector_file", "throw_ratio", "lens_shift", "cod", "background", "cam_dist",
                   "proj_dist", "no_refine", "strict", "method", "projector", "order", "step", "decode_method",
                   "shadow", "contrast", "window", "estimator")


def _path(how: str, rig: bool, method: str | None, n: int) -> str:
    """Which calibration the command runs: single-pose, multi-pose, camera-only (one photo / several photos), rig
    single-pose or rig multi-pose."""
    if rig:
        return "rig single-pose" if method == "single-pose" or (method is None and n == 1) else "rig multi-pose"
    if how == "camera-only":
        return "camera-only (one photo)" if n == 1 else "camera-only (several photos)"
    return how


def _refuse_unused(path: str, given: dict, poses) -> None:
    """Refuse (one line, exit 2) an option given to a calibration that would ignore it: what it is, what this
    calibration is, what to do.  ``given``: option -> whether it was given; ``--cod`` also goes unused with a
    fixed camera (``--camera``)."""
    for opt, is_given in given.items():
        what, applies = _APPLIES[opt]
        unused = path not in applies or (opt == "--cod" and given.get("--camera"))
        if not (is_given and unused):
            continue
        if opt == "--cod" and path in applies:
            fail("--cod is how a single-pose fit finds the camera's principal point; with --camera the camera's "
                 "intrinsics are given and fixed, so it would be ignored: leave one of them out")
        hint = ""
        if path.startswith("rig") and "single-pose" in applies and "rig single-pose" not in applies:
            hint = (f" (to use it on one pair of the rig, calibrate that pair's folder alone, e.g. procam calibrate "
                    f"{Path(poses[0]) / '<pair>'} ...)")
        elif path.startswith("rig") and "rig single-pose" in applies:
            hint = " (it applies to a rig calibrated from one rig pose)"
        elif path.startswith("rig") and "rig multi-pose" in applies:
            hint = " (it applies to a rig calibrated from several rig poses)"
        fail(f"{opt} is {what}; this is a {path} calibration, which would ignore it: leave it out{hint}")


def _left_out(dropped, n_views: int) -> list[str]:
    """The reasons of the poses left out of a multi-pose set because their board was not found (one line each,
    printed now; they join the verdict); a one-line error when fewer than two poses are left."""
    reasons = []
    for folder, why in dropped:
        why = why.split(": ", 1)[1] if why.startswith(f"{folder}: ") else why
        reasons.append(f"pose {folder} left out: {why}; calibrated from the other poses (--strict fails instead; "
                       "--detector sb, or capture the pose again with the whole board in view)")
        warn(reasons[-1])
    if dropped and n_views < 2:
        fail(f"{len(dropped)} of {len(dropped) + n_views} poses show no board ({', '.join(f for f, _ in dropped)}): "
             "a multi-pose calibration needs at least two; check --board and capture again")
    return reasons


@app.command("calibrate")
@user_errors
@with_pose_options
def calibrate_cmd(
    board: BoardOpt,
    square: SquareOpt,
    poses: list[Path] = typer.Argument(..., help="One pose folder (single-pose), several (multi-pose), or with "
                                               "--camera-only one image; rig pose folders (one sub-folder per "
                                               "camera-projector pair, docs/rigs.md) calibrate every device of a rig."),
    out: Path = typer.Option(..., "-o", "--out", help="Calibration file (.json, or .yml for OpenCV YAML)."),
    method: Method = typer.Option(None, "--method", help="Default: single for one pose, multi for several."),
    camera_only: bool = typer.Option(False, "--camera-only", help="Camera intrinsics from photos of the board: one "
                                     "(the single-pose method) or several (Zhang, with checks)."),
    camera_file: Path = typer.Option(None, "--camera", help="The camera's intrinsics from an earlier calibration "
                                     "(procam JSON; OpenCV YAML/XML of procam, kamino410 or another tool): fixed; "
                                     "one pose then calibrates the projector and R, T."),
    projector_file: Path = typer.Option(None, "--projector-intrinsics", help="The projector's intrinsics and "
                                        "distortion from an earlier calibration of it (procam JSON; OpenCV YAML/XML of "
                                        "procam, kamino410 or another tool): fixed; one pose then calibrates R, T (a "
                                        "projector that was bumped)."),
    throw_ratio: str = typer.Option(None, "--throw-ratio", help="Single-pose: the projector datasheet's throw ratio "
                                    "(distance / image width) as a prior, e.g. 1.26 or 1.26+-0.03 (default "
                                    "tolerance 0.02; docs/datasheet.md)."),
    lens_shift: str = typer.Option(None, "--lens-shift", help="Single-pose: the datasheet's lens shift H,V in "
                                   "percent of the image (positive: image right of / above the lens axis; "
                                   "docs/datasheet.md) as a prior, e.g. 0,50 or 0,50+-5 (default tolerance 2 %)."),
    yaml: Path = typer.Option(None, "--yaml", help="Also write OpenCV FileStorage YAML (cam_K, cam_kc, ...)."),
    png: Path = typer.Option(None, "--png", help="Residual plot."),
    report: Path = typer.Option(None, "--report", help="Also write the HTML report (one self-contained file)."),
    cod: Cod = typer.Option(None, "--cod", show_default="auto", help="Single-pose principal point: auto (the centre "
                            "of distortion when reliable, else the image centre as a prior), paper (always the centre "
                            "of distortion) or image-center."),
    background: BackgroundOpt = None,
    cam_dist: DistModel = typer.Option(None, "--cam-dist", show_default="auto", help="Multi-pose camera distortion "
                                       "model (auto: the richest OpenCV model whose terms the poses determine)."),
    proj_dist: DistModel = typer.Option(None, "--proj-dist", show_default="auto", help="Multi-pose projector "
                                        "distortion model."),
    no_refine: bool = typer.Option(False, "--no-refine", help="Multi-pose: skip the joint refinement."),
    strict: bool = typer.Option(False, "--strict", help="Multi-pose: fail when a pose's board is not found "
                                "(default: leave that pose out, say so, and calibrate from the others)."),
    force: bool = typer.Option(False, "--force", help="Write a degenerate or failed calibration anyway (marked as "
                                                      "such in the files; the exit code is still 3)."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
    **pose_args,
):
    """Calibrate a projector-camera pair (or, with --camera-only, a camera) and write JSON/YAML."""
    params = dict(locals())
    keep_freed_memory()
    reader = None
    if not camera_only:
        # the pose folders' images are read from here on (the first pose at once, each next one while the one
        # before is processed), while the rest of the calibration is imported and its options are checked; a
        # camera-only calibration reads photos, not pose folders
        from ..stream import Prefetcher
        from . import take_reader

        reader = take_reader(poses) or Prefetcher(poses)  # started before the parsing by procam.cli.main, or now
    importer = _import_solver_ahead(reader)
    try:
        _calibrate(reader, **params)
    finally:
        if reader is not None:
            reader.close()
        if importer is not None:
            importer.join()


def _import_solver_ahead(reader):
    """Start importing scipy's optimizer (the calibration's least squares: a tenth to a third of a second, more
    than the fit) in a thread, when a child process reads the poses (``reader.child``), so that the import runs
    while the poses are processed instead of after them; the thread, or None.

    Not beside reader threads: an import holds the interpreter lock, and each PNG a reader thread decodes needs
    the lock back several times, each waiting up to Python's switch interval (a 5-pose calibrate took 0.02-0.06 s
    longer with the import ahead than without).  With the reading in a child process the import waits only on
    this process's own work: 5-pose calibrates 9 % faster than threads without it, 5 % with the child alone
    (benchmarks/pipeline.py's data, 20 alternating rounds)."""
    import threading

    if reader is None or getattr(reader, "child", None) is None:
        return None

    def load():
        try:
            import scipy.optimize  # noqa: F401
        except ImportError:  # pragma: no cover - the calibration says so itself, where it imports it
            pass

    thread = threading.Thread(target=load, name="procam-import", daemon=True)
    thread.start()
    return thread


def _calibrate(reader, *, board, square, poses, out, method, camera_only, camera_file, projector_file, throw_ratio,
               lens_shift, yaml, png, report, cod, background, cam_dist, proj_dist, no_refine, strict, force,
               projector, order, step, pose_args):
    """:func:`calibrate_cmd`'s work, its images read by ``reader`` (a :class:`procam.stream.Prefetcher` of the
    pose folders, None for a camera-only calibration)."""
    import contextlib

    from .. import method as calibration_method
    from .. import multi_pose as _mp
    from .. import pipeline
    from . import _show

    brd = parse_board(board, square)
    how = calibration_method.choose(len(poses), "camera-only" if camera_only else _METHODS[value(method)])
    multi = how == "multi-pose"
    from ..capture import is_rig_pose

    rig = [p for p in poses if is_rig_pose(p)]
    if rig and camera_only:
        fail(f"{rig[0]}: a rig pose folder (pattern captures of each camera-projector pair); --camera-only "
             "calibrates a camera from photos of the board: leave --camera-only out, or give the photos")
    _refuse_unused(_path(how, bool(rig), _METHODS[value(method)], len(poses)),
                   dict.fromkeys(given(*_APPLIES_PARAMS), True), poses)
    cod, background = value(cod) or "auto", value(background) or "free"
    cam_dist, proj_dist = value(cam_dist) or "auto", value(proj_dist) or "auto"
    # corners a pose needs: multi-pose needs fewer per pose than single-pose (its count check is per model)
    opts = pose_options(**pose_args,
                        min_corners=_mp.MIN_CORNERS_PER_POSE if multi else 10,
                        background=not multi, poses=() if camera_only else poses)
    camera = background_options = dense_options = None  # the single-pose solver's: a multi-pose one has none
    if rig or not multi:
        from .. import single_pose as _sp
        from ..single_pose.background import BackgroundOptions

        camera, background_options = _sp.CameraOptions(cod=cod), BackgroundOptions(mode=background)
        dense_options = _dense_options(throw_ratio, lens_shift, projector_file)
    # everything that can be checked is checked before the (slow) decoding
    output_path(out, "-o", (".json", ".yml", ".yaml"), inputs=poses)
    output_path(yaml, "--yaml", (".yml", ".yaml"), inputs=poses)
    output_path(png, "--png", FIGURE_SUFFIXES, inputs=poses)
    output_path(report, "--report", (".html", ".htm"), inputs=poses)
    outs = [p.resolve() for p in (out, yaml, png, report) if p is not None]
    if len(set(outs)) < len(outs):
        fail("-o, --yaml, --png and --report must be different files")
    if rig:
        from . import _rig

        reader.close()  # a rig's pairs are read pair by pair (procam.rig), not by this reader
        distinct_poses(poses)
        rc, agreement = _rig.calibrate(poses, brd=brd, method=_METHODS[value(method)], options=opts, camera=camera,
                                       background=background_options, cam_dist=cam_dist,
                                       proj_dist=proj_dist, refine=not no_refine,
                                       projector=optional_size(projector), order=value(order), step=step)
        return finish(rc, out=out, yaml=yaml, png=png, report=report, force=force, agreement=agreement)
    left_out = []
    if camera_only:
        if yaml is not None or out.suffix.lower() in (".yml", ".yaml"):
            fail("a camera-only calibration has no projector, so no OpenCV procam YAML; write it as JSON (-o cam.json)")
        if camera_file is not None:
            fail("--camera gives the camera's intrinsics; --camera-only estimates them: use one of the two")
        views = [pipeline.camera_only_view(p, brd, options=opts) for p in poses]
    else:
        calibration_method.check(how, len(poses), unit="pose folder")
        distinct_poses(poses)
        dropped = [] if multi and not strict else None
        with console.status("decoding poses ...") if console.is_terminal else contextlib.nullcontext(), reader:
            views = pipeline.views_from_folders(poses, brd, optional_size(projector), value(order), options=opts,
                                                step=step, prefetcher=reader, dropped=dropped)
        left_out = _left_out(dropped or (), len(views))
        for v in views:
            say(f"{v.name}: {int(v.valid.sum())} of {len(v.valid)} corners")
            for w in v.diagnostics.get("warnings", []):
                warn(w)
    known = known_projector = None
    if camera_file is not None:
        from ..io import load_camera_intrinsics

        known = load_camera_intrinsics(camera_file, views[0].cam_size)
    if projector_file is not None:
        from ..io import load_projector_intrinsics

        known_projector = load_projector_intrinsics(projector_file, views[0].proj_size)
    from ..errors import DegeneratePoseError
    from ..verdict import with_evidence

    try:
        calib = calibration_method.calibrate(views, method=how, known_camera=known, camera=camera,
                                             background=background_options,
                                             cam_dist=cam_dist, proj_dist=proj_dist,
                                             refine=not no_refine, known_projector=known_projector,
                                             dense=dense_options)
    except DegeneratePoseError as e:  # no result at all: nothing to write, even with --force
        fail(f"degenerate: {e}", code=3, label="not trusted")
    if left_out:
        from ..verdict import with_reasons

        calib = with_reasons(calib, [("weak", r) for r in left_out])
    check = None
    if calib.projector is not None:  # the metric verification: in-sample, and leave-one-out with >= 4 poses
        from ..verify import verify_calibration

        check = verify_calibration(calib)
        calib = with_evidence(calib, check)  # its verdict consults the verification before anything is written
    _show.print_calibration(calib, check)
    if check is not None:
        _show.print_verification(check)
        if check.leave_one_out is not None and check.leave_one_out.refits:
            _show.print_spread(calib, check.leave_one_out.refits)
    finish(calib, out=out, yaml=yaml, png=png, report=report, force=force, check=check)


def finish(result, *, out: Path, yaml: Path | None, png: Path | None, report: Path | None, force: bool, check=None,
           agreement=None) -> None:
    """The one end of every calibration the command makes, a pair's (:class:`~procam.calibration.Calibration`)
    or a rig's (:class:`~procam.calibration.RigCalibration`): refuse to write one that must not be trusted unless
    ``force``; write ``out`` (JSON or YAML) and ``yaml``, the figure ``png`` (the pair's residuals, the rig's
    drawing) and the HTML ``report``; exit 3 after writing an untrusted one.  ``check``: the pair's metric
    verification; ``agreement``: the rig's."""
    from .. import io

    rig = agreement is not None or not hasattr(result, "camera")
    what = "rig calibration" if rig else "calibration"
    if not result.trusted and not force:
        fail(f"{result.verdict} {what}, not written: {'; '.join(result.verdict_reasons) or result.verdict} "
             "(--force writes it anyway, marked as such)", code=3, label="not trusted")
    if rig:
        from ..io.rig import check_rig_yaml, save_rig_calibration

        for path in (out, yaml):  # a YAML/XML the rig's device names cannot be written as: before any write
            if path is not None and path.suffix.lower() in (".yml", ".yaml", ".xml"):
                check_rig_yaml(result, path)
        save, save_yaml = save_rig_calibration, save_rig_calibration
    else:
        save, save_yaml = io.save_calibration, io.save_opencv_yaml
    save(result, out)
    say(f"wrote {out}" + ("" if result.trusted else f" (marked {result.verdict})"))
    if yaml is not None:
        save_yaml(result, yaml)
        say(f"wrote {yaml}")
    if png is not None:
        from ..plots import save_figure

        save_figure(_figure(result, rig, agreement, out.name), png)
        say(f"wrote {png}")
    if report is not None:
        if rig:
            from ._rig import write_report

            write_report(result, report, agreement=agreement, name=out.name)
        else:
            from . import _show

            _show.write_calibration_report(result, report, check=check, name=out.name)
    if not result.trusted:
        fail(f"{result.verdict} {what} (written because of --force): "
             f"{'; '.join(result.verdict_reasons) or result.verdict}", code=3, label="not trusted")


def _figure(result, rig: bool, agreement, name: str):
    """The figure of ``--png``: a rig's drawing, a pair's residuals."""
    if rig:
        from ..rig.draw import rig_figure

        return rig_figure(result, agreement, title=name)
    from ..plots.residuals import residual_figure
    from ..residuals import calibration_residuals
    from ..verdict import calibration_verdict

    return residual_figure(calibration_residuals(result), result.camera.image_size,
                           result.projector.image_size if result.projector is not None else None,
                           title=f"{name}: {result.method}", verdict=calibration_verdict(result).line())
