"""``procam export``: a calibration for other tools (OpenGL/Unity matrices, remap tables, kamino410 XML)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Optional

import typer

from .. import choices
from ._app import ForceOpt, app, choice, fail, number, output_dir, output_path, say, user_errors, value

Format = choice("Format", choices.EXPORT_FORMATS)
World = choice("World", choices.WORLDS)


@app.command("export")
@user_errors
def export_cmd(
    calibration: Path = typer.Argument(..., help="Calibration file (JSON or OpenCV YAML)."),
    fmt: Format = typer.Option(..., "--format", help="opengl (JSON with projection/view matrices), maps (remap "
                                                 "tables, .npz, into a folder) or kamino410 (their XML)."),
    out: Path = typer.Option(..., "-o", "--out", help="Output file (opengl: .json; kamino410: .xml) or folder (maps)."),
    near: Optional[float] = typer.Option(None, "--near", help="opengl: near clipping distance, calibration units."),
    far: Optional[float] = typer.Option(None, "--far", help="opengl: far clipping distance, calibration units."),
    world: World = typer.Option(World.camera, "--world", help="opengl: world frame, camera or projector."),
    y_down: bool = typer.Option(False, "--y-down", help="opengl: NDC y down (Vulkan) instead of up (OpenGL, Unity)."),
    zero_to_one: bool = typer.Option(False, "--zero-to-one", help="opengl: NDC depth 0..1 instead of -1..1."),
    rectify: bool = typer.Option(False, "--rectify", help="maps: also the stereo rectification maps of both devices."),
    scale: float = typer.Option(1.0, "--scale", help="maps --rectify: rectified focal length in units of the "
                                                     "camera's."),
    force: ForceOpt = False,
):
    """Write the calibration in the form the next tool wants (see docs/exports.md)."""
    import numpy as np

    from .. import export as _ex
    from .. import io
    from ..io.files import to_jsonable, write_text

    fmt, world = value(fmt), value(world)
    if fmt == "opengl":
        output_path(out, "-o", (".json",), inputs=(calibration,))
        if near is None or far is None:
            fail("--format opengl needs --near and --far (clipping distances in the calibration's units, e.g. mm)")
        if not (math.isfinite(near) and math.isfinite(far) and 0 < near < far <= 1e12):
            fail(f"--near and --far must be finite with 0 < near < far <= 1e12, got {near} and {far}")
        if far / near > 1e7:
            fail(f"--far / --near is {far / near:.3g}; at most 1e7 (a depth buffer has no precision left beyond), "
                 "so raise --near")
    elif fmt == "kamino410":
        output_path(out, "-o", (".xml", ".yml", ".yaml"), inputs=(calibration,))
    else:
        if out.exists() and not out.is_dir():
            fail(f"-o {out}: --format maps writes several files; give a folder")
        number(scale, "--scale", lo=0.1, hi=10, what="a focal-length factor")
        output_dir(out, "-o", "export", force)
    calib = io.load_calibration(calibration)
    if calib.projector is None or calib.R is None:
        fail(f"{calibration}: a camera-only calibration has no projector to export; give a procam calibration")
    if fmt == "opengl":
        doc = _ex.opengl_document(calib, near, far, world=world, y_up=not y_down, zero_to_one=zero_to_one)
        doc["calibration"] = str(calibration)
        write_text(out, json.dumps(to_jsonable(doc), indent=1))
        say(f"wrote {out}")
    elif fmt == "kamino410":
        io.save_kamino410(calib, out)
        say(f"wrote {out}")
        if calib.camera.distortion.model == "division":
            say("note: the camera's division model is written as its OpenCV (k1, k2, p1, p2, k3) fit")
    else:
        output_dir(out, "-o", "export", force, create=True)
        written = []
        cam, proj = calib.camera, calib.projector
        mx, my = _ex.undistort_maps(cam)
        written.append(io.save_maps(out / "camera_undistort.npz", mx, my, K=cam.K, new_K=cam.K,
                                   size=np.array(cam.image_size)))
        mx, my = _ex.predistort_maps(proj)
        written.append(io.save_maps(out / "projector_predistort.npz", mx, my, K=proj.K, K_ideal=proj.K,
                                   size=np.array(proj.image_size)))
        if rectify:
            rect = _ex.stereo_rectify(calib, scale=scale)
            for name, dev, k in (("camera", cam, "1"), ("projector", proj, "2")):
                mx, my = _ex.undistort_maps(dev, new_K=rect["P" + k][:, :3], R=rect["R" + k], size=rect["size" + k])
                written.append(io.save_maps(out / f"{name}_rectify.npz", mx, my, R=rect["R" + k], P=rect["P" + k],
                                           size=np.array(rect["size" + k])))
        for p in written:
            say(f"wrote {p}")
