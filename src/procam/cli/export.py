"""``procam export``: a calibration for other tools (Blender, Unity, OpenGL/TouchDesigner, remap tables, kamino410
XML, OpenCV YAML) and the projector's view of a pose."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from .. import choices
from ._app import app, fail, say, user_errors, warn
from ._options import ForceOpt, OrderOpt, ProjectorOpt, StepOpt, choice, number, optional_size, value
from ._paths import distrust, load_pose, output_dir, output_path

Format = choice("Format", choices.EXPORT_FORMATS)
World = choice("World", choices.WORLDS)
Unit = choice("Unit", choices.LENGTH_UNITS)

#: The output file suffixes of each file format (``maps`` writes a folder).
SUFFIXES = {"opengl": (".json",), "blender": (".json",), "unity": (".json",), "kamino410": (".xml", ".yml", ".yaml"),
            "yaml": (".yml", ".yaml", ".xml"), "projector-view": (".png",)}
ENGINES = ("opengl", "blender", "unity")


def _clip(fmt: str, near, far, unit: str):
    """``(near, far)`` checked, in the calibration's unit (opengl) or in metres (blender, unity: None = the
    engine's defaults)."""
    if near is None and far is None and fmt != "opengl":
        return None, None
    if near is None or far is None:
        fail(f"--format {fmt} needs --near and --far together (clipping distances in the calibration's units, "
             "e.g. mm)" + ("" if fmt == "opengl" else "; leave both out for the engine's defaults"))
    from ..errors import CalibrationError
    from ..export.frames import check_clip, metres_per_unit

    try:
        near, far = check_clip(near, far)
    except CalibrationError as e:
        fail(f"--near {near:g} and --far {far:g}: {e}")
    if fmt == "opengl":
        return near, far

    return near * metres_per_unit(unit), far * metres_per_unit(unit)


#: The files of ``--format maps`` in its folder, and those ``--rectify`` adds.
MAPS_FILES = ("camera_undistort.npz", "projector_predistort.npz")
RECTIFY_FILES = ("camera_rectify.npz", "projector_rectify.npz")


def _check_outputs(fmt, out, calibration, inputs, force, rectify=False):
    """Every output file checked before any work (the neighbours an export writes beside ``out`` too, each file of
    a maps folder: ``--force`` lets the export write beside other files, never over one procam did not write)."""
    if fmt == "maps":
        if out.exists() and not out.is_dir():
            fail(f"-o {out}: --format maps writes several files; give a folder")
        output_dir(out, "-o", "export", force, inputs=inputs)
        for name in MAPS_FILES + (RECTIFY_FILES if rectify else ()):
            output_path(out / name, "-o", (".npz",), inputs=inputs)
        return
    output_path(out, "-o", SUFFIXES[fmt], inputs=inputs)
    if fmt == "blender":
        from ..io.engines import blender_script_path

        output_path(blender_script_path(out), "-o (its script)", (".py",), inputs=inputs)
    if fmt == "projector-view":
        from ..io.engines import projector_view_paths

        output_path(projector_view_paths(out)[1], "-o (its mask)", (".png",), inputs=inputs)


def _distortion(calib, out):
    """Write the distortion maps beside an engine export; returns the document entry and says what was written."""
    from ..export.maps import distortion_maps
    from ..io.engines import distortion_map_paths, save_distortion_maps

    with_lens = [n for n in ("camera", "projector") if getattr(calib, n).distortion.model != "none"]
    for npz, png in distortion_map_paths(out, with_lens).values():
        output_path(npz, "-o (its distortion map)", (".npz",), inputs=(out,))
        output_path(png, "-o (its distortion map)", (".png",), inputs=(out,))
    maps = save_distortion_maps(out, distortion_maps(calib))
    for name, m in maps.items():
        say(f"wrote {out.parent / m['remap']} and {out.parent / m['st_map']} ({name} lens distortion, which the "
            f"engine camera cannot hold: {m['what']} maps)")
    return maps


def _projector_view(calib, out, pose, maps_file, projector, order, step):
    from .. import decode, io
    from ..export.projector_view import projector_view

    if pose is None:
        fail("--format projector-view needs --pose POSE_DIR (the captured pose whose white frame, or mean of the "
             "fringes without one, it remaps)")
    cap, calib = load_pose(pose, projector, calib, order, step)
    ps = cap.pattern_set
    if maps_file is not None:
        m = io.load_decoded_maps(maps_file)
        if m["col"].shape != cap.stack.shape[1:] or tuple(m["projector_size"]) != (ps.width, ps.height):
            fail(f"--maps {maps_file}: its maps are not of {pose} (another camera size or projector size)")
        if m["source"] and m["source"] != cap.fingerprint:
            fail(f"--maps {maps_file}: its maps were decoded from another capture, not {pose} (procam decode {pose} "
                 "-o writes that pose's maps)")
        if not m["source"]:
            warn(f"--maps {maps_file}: it does not say which capture it was decoded from (an older procam wrote it); "
                 f"it is taken as {pose}'s maps (procam decode {pose} -o writes them again with their source)")
        col, row, valid = m["col"], m["row"], m["valid_col"] & m["valid_row"]
    else:
        d = decode.decode(cap.stack, ps)
        col, row, valid = d.col, d.row, d.valid_col & d.valid_row
    view = projector_view(col, row, valid, cap.picture(), (ps.width, ps.height))
    if not view.mask.any():
        if maps_file is not None:  # the maps say so, not the pose
            fail(f"--maps {maps_file}: its maps mark no pixel decoded; decode the pose again (procam decode {pose} -o "
                 f"{maps_file.name} --png decoded.png shows what decodes)")
        fail(f"{pose}: nothing was decoded; check the decode picture (procam decode --png)")
    written = io.engines.save_projector_view(view, out)
    say(f"wrote {written[0]} (the camera's view in {ps.width}x{ps.height} projector pixels) and {written[1]} (the "
        f"decoded-valid mask: {view.coverage:.0%} of the projector)")


@app.command("export")
@user_errors
def export_cmd(
    calibration: Path = typer.Argument(..., help="Calibration file (procam JSON or YAML, OpenCV YAML/XML, kamino410 "
                                                 "XML)."),
    fmt: Format = typer.Option(..., "--format", help="blender (JSON + script), unity (JSON), opengl (JSON with "
                                                     "projection/view matrices, TouchDesigner too), maps (remap "
                                                     "tables, .npz, into a folder), kamino410 (their XML), yaml "
                                                     "(OpenCV FileStorage with procam's keys) or projector-view (PNG "
                                                     "of a pose seen from the projector)."),
    out: Path = typer.Option(..., "-o", "--out", help="Output file (.json; kamino410 .xml; yaml .yml/.xml; "
                                                    "projector-view .png) or folder (maps)."),
    near: Optional[float] = typer.Option(None, "--near", help="Near clipping distance, calibration units (opengl: "
                                                              "required; blender, unity: default the engine's)."),
    far: Optional[float] = typer.Option(None, "--far", help="Far clipping distance, calibration units."),
    world: Optional[World] = typer.Option(None, "--world", help="Engines: the device whose frame is the world, taken "
                                                                "as mounted upright (default: camera)."),
    unit: Optional[Unit] = typer.Option(None, "--unit", help="blender, unity: the calibration's length unit (the "
                                                            "board's square), turned into metres (default: mm)."),
    y_down: bool = typer.Option(False, "--y-down", help="opengl: NDC y down (Vulkan) instead of up (OpenGL, Unity)."),
    zero_to_one: bool = typer.Option(False, "--zero-to-one", help="opengl: NDC depth 0..1 instead of -1..1."),
    rectify: bool = typer.Option(False, "--rectify", help="maps: also the stereo rectification maps of both devices."),
    scale: Optional[float] = typer.Option(None, "--scale", help="maps --rectify: rectified focal length in units of "
                                                               "the camera's (default 1)."),
    pose: Optional[Path] = typer.Option(None, "--pose", help="projector-view: the pose folder (its white frame, or "
                                                             "the mean of the fringes without one)."),
    maps_file: Optional[Path] = typer.Option(None, "--maps", help="projector-view: the pose's decoded maps (procam "
                                                                 "decode -o), instead of decoding it again."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
    pair: Optional[str] = typer.Option(None, "--pair", help="A rig calibration: the pair to export (camera/projector, "
                                                           "or a device's name); each pair in its camera's frame, "
                                                           "the rig's reference camera for a one-camera rig."),
    force: ForceOpt = False,
):
    """Write the calibration in the form the next tool wants (see docs/exports.md)."""
    from .. import io

    fmt = value(fmt)
    inputs = tuple(p for p in (calibration, pose, maps_file) if p is not None)
    _check_outputs(fmt, out, calibration, inputs, force, rectify)
    for opt, given, fmts in (("--pose", pose, ("projector-view",)), ("--maps", maps_file, ("projector-view",)),
                             ("--order", order, ("projector-view",)), ("--step", step, ("projector-view",)),
                             ("--rectify", rectify, ("maps",)), ("--scale", scale, ("maps",)),
                             ("--y-down", y_down, ("opengl",)), ("--zero-to-one", zero_to_one, ("opengl",)),
                             ("--near", near, ENGINES), ("--far", far, ENGINES), ("--world", world, ENGINES),
                             ("--unit", unit, ("blender", "unity")), ("--force", force, ("maps",))):
        if given is not None and given is not False and fmt not in fmts:
            fail(f"{opt} belongs to --format {' or '.join(fmts)}, not {fmt}; leave it out")
    if scale is not None and not rectify:
        fail("--scale is the rectified images' focal length: it belongs to --rectify; add --rectify or leave it out")
    world, unit, scale = value(world) or "camera", value(unit) or "mm", 1.0 if scale is None else scale
    clip = _clip(fmt, near, far, unit) if fmt in ENGINES else (None, None)
    if fmt == "maps":
        number(scale, "--scale", lo=0.1, hi=10, what="a focal-length factor")
    calib = io.load_calibration(calibration, pair=pair)
    if projector is not None and fmt != "projector-view" and calib.projector is not None:
        size = optional_size(projector)
        calib = io.complete_sizes(calib, proj_size=size)
        if tuple(calib.projector.image_size) != tuple(size):
            fail(f"--projector {projector}: {calibration} stores a {calib.projector.image_size[0]}x"
                 f"{calib.projector.image_size[1]} projector; leave --projector out (it is for files that store no "
                 "projector size, like kamino410's)")
    for w in calib.warnings:   # a size the file does not store (kamino410's, other tools' files) is said
        if "does not store the projector size" in w:
            warn(w + " (--projector WIDTHxHEIGHT)")
        elif "does not store the camera size" in w:
            warn(w + " (the exported camera is for images of that size)")
    if calib.projector is None or calib.R is None:
        fail(f"{calibration}: a camera-only calibration has no projector to export; give a procam calibration")
    doubt = distrust(calib, calibration)
    if doubt:
        warn(doubt)
    if fmt == "projector-view":
        _projector_view(calib, out, pose, maps_file, projector, order, step)
    elif fmt in ENGINES:
        from .. import export as _ex

        if fmt == "opengl":
            doc = _ex.opengl_document(calib, *clip, world=world, y_up=not y_down, zero_to_one=zero_to_one)
        elif fmt == "blender":
            doc = _ex.blender_document(calib, world=world, unit=unit, near_m=clip[0], far_m=clip[1])
        else:
            doc = _ex.unity_document(calib, world=world, unit=unit, near_m=clip[0], far_m=clip[1])
        doc["calibration"] = Path(calibration).name
        if doubt:
            doc["not_trusted"] = doubt
        doc["distortion_maps"] = _distortion(calib, out)
        written = (io.engines.save_blender(doc, out, _ex.blender.script_text()) if fmt == "blender"
                   else [io.engines.save_document(doc, out)])
        for p in written:
            say(f"wrote {p}")
        if not doc["distortion_maps"]:
            say("neither device has lens distortion: the engine cameras are the whole calibration")
    elif fmt in ("kamino410", "yaml"):
        (io.save_kamino410 if fmt == "kamino410" else io.save_opencv_yaml)(calib, out)
        say(f"wrote {out}")
        if calib.camera.distortion.model == "division":
            say("note: the camera's division model is written as its OpenCV (k1, k2, p1, p2, k3) fit")
    else:
        _maps(calib, out, force, rectify, scale)
    if doubt:
        fail(f"the export is of a calibration that must not be trusted: its verdict is {calib.verdict}", code=3,
             label="not trusted")


def _maps(calib, out, force, rectify, scale):
    import numpy as np

    from .. import export as _ex
    from .. import io

    output_dir(out, "-o", "export", force, create=True)
    written = []
    cam, proj = calib.camera, calib.projector
    mx, my = _ex.undistort_maps(cam)
    written.append(io.save_maps(out / MAPS_FILES[0], mx, my, K=cam.K, new_K=cam.K, size=np.array(cam.image_size)))
    mx, my = _ex.predistort_maps(proj)
    written.append(io.save_maps(out / MAPS_FILES[1], mx, my, K=proj.K, K_ideal=proj.K,
                                size=np.array(proj.image_size)))
    if rectify:
        from ..export.rectify import turn_words

        rect = _ex.stereo_rectify(calib, scale=scale)
        for name, dev, k in (("camera", cam, "1"), ("projector", proj, "2")):
            mx, my = _ex.undistort_maps(dev, new_K=rect["P" + k][:, :3], R=rect["R" + k], size=rect["size" + k])
            turn = rect["rows_along_deg"][name]
            written.append(io.save_maps(out / RECTIFY_FILES[int(k) - 1], mx, my, R=rect["R" + k], P=rect["P" + k],
                                        Q=rect["Q"], size=np.array(rect["size" + k]), rows_along_deg=np.array(turn)))
            say(f"{name}: rectified image {rect['size' + k][0]}x{rect['size' + k][1]}, {turn_words(turn)} "
                f"(its rows run at {turn:+.1f} deg in the {name}'s image)")
    for p in written:
        say(f"wrote {p}")
