"""What ``procam calibrate``, ``procam simulate`` and ``procam export`` do with a rig (several projectors or
cameras, :mod:`procam.rig`): a helper of those commands, not a command; it parses nothing, it calls the library
and prints its tables."""

from __future__ import annotations

from pathlib import Path

from ._app import console, fail, plain, say, warn


def calibrate(poses, *, brd, method: str | None, options, camera, background, cam_dist: str, proj_dist: str,
              refine: bool, projector=None, order=None, step=None):
    """Calibrate the rig of rig pose folders ``poses``, print it and verify it: ``(RigCalibration, agreement)``
    for the calibrate command's one finish (:func:`procam.cli.calibrate.finish`: write, draw, report, exit 3 when
    it must not be trusted)."""
    from .. import capture
    from .. import method as calibration_method
    from ..rig import calibrate_rig, rig_views_from_folders
    from ..rig.verify import verify_rig

    not_rig = [str(p) for p in poses if not capture.is_rig_pose(p)]
    if not_rig:
        fail(f"{not_rig[0]}: not a rig pose folder, while {poses[0] if str(poses[0]) != not_rig[0] else 'another'} "
             "is; give rig pose folders only (one sub-folder per camera-projector pair) or ordinary ones only")
    calibration_method.check(calibration_method.choose(len(poses), method), len(poses), unit="rig pose folder")
    views = rig_views_from_folders(poses, brd, projector, order, options=options, step=step)
    for pv in views:
        for (c, p), v in pv.views.items():
            say(f"{pv.name} ({c}, {p}): {int(v.valid.sum())} of {len(v.valid)} corners")
            for w in v.diagnostics.get("warnings", []):
                warn(w)
    rc = calibrate_rig(views, method=method, camera=camera, background=background, cam_dist=cam_dist,
                       proj_dist=proj_dist, refine=refine)
    print_rig(rc)
    agreement = verify_rig(rc, views)
    print_agreement(agreement)
    return rc, agreement


def print_rig(rc) -> None:
    """The rig's devices (intrinsics ± std, centre, verdict) and relative poses (baseline, T, angles ± std)."""
    from ..rig.tables import device_table, relative_table
    from ._show import rich_table

    console.print(rich_table(device_table(rc), plain(f"rig calibration ({rc.method}); reference camera "
                                                     f"{rc.reference}; ± 1 sigma")))
    console.print(rich_table(relative_table(rc), plain("relative poses x_b = R x_a + T (board units, degrees)")))
    say(rc.uncertainty)
    for w in rc.warnings:
        warn(w)


def print_agreement(agreement) -> None:
    """The pairs' 3-D agreement (:func:`procam.rig.verify.verify_rig`)."""
    if not agreement:
        return
    from ..rig.tables import agreement_table
    from ._show import rich_table

    console.print(rich_table(agreement_table(agreement),
                             plain("rig verification: the same corners triangulated by two pairs (reference frame)")))


def write_report(rc, path: Path, *, poses=None, agreement=None, name: str | None = None) -> None:
    """Build and write the HTML page of the rig calibration ``rc`` (:func:`procam.report.build_rig_report`)."""
    from ..report import build_rig_report
    from ..report import write_report as write_page

    text = build_rig_report(rc, poses, agreement=agreement, name=name or path.stem)
    write_page(text, path)
    say(f"wrote {path} ({len(text.encode('utf-8')) / 1e6:.2f} MB)")


def report(calibration: Path, poses, *, out: Path, brd, projector=None, order=None, step=None, options=None) -> None:
    """``procam report`` of a rig calibration file: its page, verified on the rig pose folders ``poses`` when
    given (else on the poses its pairs keep)."""
    from ..io import load_rig_calibration

    rc = load_rig_calibration(calibration)
    views = None
    if poses:
        from .. import capture
        from ..rig import rig_views_from_folders

        not_rig = [str(p) for p in poses if not capture.is_rig_pose(p)]
        if not_rig:
            fail(f"{not_rig[0]}: not a rig pose folder; {calibration} is a rig calibration, so give rig pose folders "
                 "(one sub-folder per camera-projector pair)")
        views = rig_views_from_folders(poses, brd, projector, order, options=options, step=step)
        names = {d.name for d in rc.devices}
        for pv in views:
            unknown = [n for n in pv.cameras + pv.projectors if n not in names]
            if unknown:
                fail(f"{pv.name}: device {unknown[0]!r} is not in {calibration} (devices: {', '.join(sorted(names))})")
    write_report(rc, out, poses=views, name=calibration.name)


def capture_projectors(spec: str, virtual: bool, display, poses: int, advise: bool):
    """The projectors of ``procam capture --rig SPEC`` (:func:`procam.acquire.rig.parse_rig_projectors`), every
    option that cannot go with a rig refused first (one line, exit 2)."""
    from ..acquire.rig import parse_rig_projectors

    for flag, given in (("--display", display is not None), ("--poses", poses != 1), ("--advise", advise)):
        if given:
            fail(f"--rig captures one rig pose with each projector on its own display: leave out {flag} "
                 "(NAME=DISPLAY gives the displays; capture the next pose into another folder)")
    try:
        projectors = parse_rig_projectors(spec)
    except ValueError as e:
        fail(f"--rig {spec}: {e}")
    if virtual and len(projectors) != 2:
        fail(f"--rig {spec}: the virtual rig has two projectors; name two")
    missing = [p.name for p in projectors if p.display is None]
    if missing and not virtual:
        fail(f"--rig {spec}: give {missing[0]}'s display (NAME=DISPLAY; --list-devices lists them)")
    return projectors


def capture(out_dir: Path, projectors, rig, options, *, board, hooks) -> None:
    """Capture one rig pose (:func:`procam.acquire.rig.capture_rig_pose`), saying which projector's turn it is."""
    from ..acquire.rig import capture_rig_pose

    def announce(i, n, p):
        where = "virtual" if rig.virtual else f"display {p.display}"
        say(f"projector {i + 1}/{n}: {p.name} ({where}) -- the board and the camera stay still")

    capture_rig_pose(out_dir, projectors, rig, options, board=board, hooks=hooks, announce=announce)
    say(f"wrote rig pose {out_dir}: rig.json and one pose folder per projector "
        f"({', '.join(p.name for p in projectors)}); procam calibrate reads it")


def _check_rig_dir(out_dir: Path, rig, order: str, force: bool) -> None:
    """Before rendering: the rig folder, its own files and each pair's folder take the simulator's output, and none
    of them holds a file procam did not write under a name it writes (raises :class:`~procam.errors.OutputError`)."""
    from .. import capture, patterns
    from ..io.folders import prepare_output_dir
    from ._paths import output_path

    prepare_output_dir(out_dir, "simulate", force=force, option="OUT_DIR", create=False)
    for name in (capture.RIG_MANIFEST, "truth.json"):
        output_path(out_dir / name, "OUT_DIR", (".json",))
    devices = {d.name: d for d in rig.projectors}
    nc, npj = len(rig.cameras), len(rig.projectors)
    for c, p in rig.pairs():
        ps = patterns.pattern_set(*devices[p].size, order)
        capture.check_sequence_dir(out_dir / capture.pair_folder_name(c, p, nc, npj), ps, writer="simulate",
                                   force=force, extra=("truth.json",), option="OUT_DIR")


def simulate(out_dir: Path, rig_name: str, angles, distance, changes: dict, seed: int, order: str, force: bool) -> None:
    """Render the preset rig ``rig_name`` at board ``angles`` (reference camera frame) and write it as a rig pose
    folder (:func:`procam.simulate.write_rig_capture`)."""
    from .. import simulate as sim

    rig = sim.rig_preset(rig_name)
    rig = rig.with_board_pose(angles, distance=distance)
    if rig.fit_margin() < 0:
        warn(f"part of the board is outside some device's image (by {-rig.fit_margin():.0f} px); some corners may "
             "be missing - try a larger --distance or smaller angles")
    _check_rig_dir(out_dir, rig, order, force)
    rendered = sim.render_rig(rig, order=order, seed=seed, changes=changes)
    folders = sim.write_rig_capture(out_dir, rig, rendered, order=order, force=force)
    names = ", ".join(f"{f.name} ({c}, {p})" for f, (c, p, _, _) in zip(folders, rendered.values()))
    say(f"wrote rig {rig_name} to {out_dir}: rig.json, truth.json and one pose folder per pair: {names}")
