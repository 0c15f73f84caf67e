"""``procam demo``: render a synthetic capture and run the whole pipeline on it."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import typer

from ._app import app, console, fail, say, user_errors
from ._options import ForceOpt, SimPreset, number, value
from ._paths import output_dir, output_path

#: The files the demo writes beside its capture folder (name, suffix).
DEMO_FILES = (("calib.json", ".json"), ("calib.yml", ".yml"), ("decode.png", ".png"), ("corners.png", ".png"),
              ("demo_summary.json", ".json"))


def _row(t, name, true, est, std=None, fmt=".2f"):
    err = est - true
    t.add_row(name, f"{true:{fmt}}", f"{est:{fmt}}", f"{err:+{fmt}}", "" if std is None or not math.isfinite(std)
              else f"{std:{fmt}}")


@app.command("demo")
@user_errors
def demo_cmd(
    out_dir: Path = typer.Argument(Path("procam-demo"), help="Folder for the capture and the results."),
    preset: SimPreset = typer.Option(SimPreset.ideal, "--preset", help="Simulated rig: ideal (the method's "
                                     "assumptions hold), paper (the seed paper's rig, u0p != W/2) or another of "
                                     "procam simulate's."),
    seed: int = typer.Option(0, "--seed", help="Noise seed."),
    force: ForceOpt = False,
):
    """Render a procam capture at a recommended pose, calibrate it from that one pose, compare with the truth."""
    import numpy as np
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
    from rich.table import Table

    # the simulator, the solvers and matplotlib load only when the demo runs, not with every command
    from .. import io, patterns, pipeline, simulate, single_pose
    from ..board import Board
    from ..io import files as _files
    from ..models import euler_deg
    from ..plots import save_figure
    from ..plots.correspond import correspond_figure
    from ..plots.decode import decode_figure
    from ..stats import rms
    from . import _show

    preset = value(preset)
    if preset not in simulate.PRESETS:
        fail(f"--preset must be one of {', '.join(simulate.PRESETS)}, got {preset!r}")
    number(seed, "--seed", lo=0, hi=2**32 - 1, what="a seed")
    output_dir(out_dir, "OUT_DIR", "demo", force)
    for name, suffix in DEMO_FILES:  # each of its files, and its capture folder, before any work
        output_path(out_dir / name, "OUT_DIR", (suffix,))
    from .. import capture
    from ..errors import OutputError

    try:
        capture.check_sequence_dir(out_dir / "capture", patterns.pattern_set(*simulate.preset(preset).proj_size),
                                   writer="simulate", force=force, extra=("truth.json",), option="OUT_DIR")
    except OutputError as e:
        fail(str(e))
    # 2x2 supersamples instead of the preset's 3x3: half the rendering time, the same errors against the truth
    # (seeds 0-2, 'ideal': corner RMS camera 0.0092-0.0097 px vs 0.0090-0.0096, projector 0.024-0.026 vs
    # 0.023-0.025; the parameters' errors differ by less than from seed to seed)
    scene = simulate.with_board_pose(simulate.preset(preset), simulate.RECOMMENDED_POSE).replace(supersample=2)
    cap_dir = out_dir / "capture"
    t0 = time.perf_counter()
    with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                  TimeElapsedColumn(), console=console.real, transient=not console.is_terminal) as prog:
        task = prog.add_task(f"rendering '{preset}' scene", total=1)

        def cb(done, total):
            prog.update(task, completed=done, total=total)

        stack, truth = simulate.render(scene, seed=seed, progress=cb)
    output_dir(out_dir, "OUT_DIR", "demo", force, create=True)
    simulate.write_capture(cap_dir, stack, truth, force=force)
    say(f"rendered {len(stack)} images {stack.shape[2]}x{stack.shape[1]} in {time.perf_counter() - t0:.1f} s -> "
        f"{cap_dir}")
    ps = patterns.pattern_set(*truth["projector"]["size"])
    t0 = time.perf_counter()
    brd = Board(truth["board"]["cols"], truth["board"]["rows"], truth["board"]["square"])
    view, maps = pipeline.view_from_stack(stack, ps, brd, name=str(cap_dir))
    c = truth["corners"]
    e_cam = view.cam_pts - np.array(c["camera_distorted"])
    e_proj = view.proj_pts - np.array(c["projector"])
    console.print(f"decoded {maps.valid.mean() * 100:.1f} % of the pixels; {int(view.valid.sum())}/{len(view.valid)} "
                  "corners; "
                  f"corner error vs truth: camera {rms(e_cam):.3f} px RMS, "
                  f"projector {rms(e_proj):.3f} px RMS "
                  f"({time.perf_counter() - t0:.1f} s)")
    calib = single_pose.calibrate(view)
    _show.print_calibration(calib)
    cal_json, cal_yml, dec_png, cor_png, summary_json = (out_dir / n for n, _ in DEMO_FILES)
    io.save_calibration(calib, cal_json)
    io.save_opencv_yaml(calib, cal_yml)
    save_figure(decode_figure(maps, stack[ps.white], title="demo: decoded maps"), dec_png)
    save_figure(correspond_figure(view, stack[ps.white], title="demo: correspondences"), cor_png)

    t = Table(title=f"single-pose estimate vs truth ('{preset}' preset, pose {simulate.RECOMMENDED_POSE} deg)")
    for col in ("parameter", "true", "estimated", "error", "± std"):
        t.add_column(col, justify="right" if col != "parameter" else "left")
    cam, proj = truth["camera"], truth["projector"]
    K, Kp, std = calib.camera.K, calib.projector.K, calib.std
    _row(t, "camera f (px)", cam["f"], K[0, 0], std.get("f_c"))
    _row(t, "camera alpha", cam["alpha"], K[1, 1] / K[0, 0], std.get("alpha_c"), ".4f")
    _row(t, "camera u0 (px)", cam["u0"], K[0, 2], std.get("u0c"))
    _row(t, "camera v0 (px)", cam["v0"], K[1, 2], std.get("v0c"))
    d = calib.camera.distortion
    if d.model == "division" and cam["distortion"]["model"] == "division":
        _row(t, "camera k1 (1e-8 px^-2)", cam["distortion"]["k1"] * 1e8, d.k1 * 1e8,
             None if std.get("k1") is None else std["k1"] * 1e8)
    _row(t, "projector f (px)", proj["f"], Kp[0, 0], std.get("f_p"))
    from ..summary import projector_assumptions, projector_freed

    freed = projector_freed(calib)
    if "u0p" in freed:
        _row(t, "projector u0 (px, from the background)", proj["u0"], Kp[0, 2], std.get("u0p"))
    else:
        _row(t, "projector u0 (px, fixed W/2)", proj["u0"], Kp[0, 2])
    _row(t, "projector v0 (px)", proj["v0"], Kp[1, 2], std.get("v0p"))
    eul = euler_deg(calib.R)
    rstd = std.get("R_euler_deg") or [None] * 3
    tstd = std.get("T") or [None] * 3
    for i, n in enumerate(("psi", "nu", "phi")):
        _row(t, f"R {n} (deg)", truth["extrinsics"]["angles_deg"][i], eul[i], rstd[i], ".3f")
    for i, n in enumerate("XYZ"):
        _row(t, f"T {n} (mm)", truth["extrinsics"]["T"][i], float(calib.T[i]), tstd[i])
    console.print(t)
    if preset == "paper" and "u0p" in freed:
        console.print("note: the 'paper' rig's projector has u0 = 1013 px, but the paper's single-pose method assumes "
                      "u0 = W/2 = 960; the background behind the board refuted that and procam estimated u0 from it.")
    elif preset == "paper":
        console.print("note: the 'paper' rig's projector has u0 = 1013 px, but the single-pose model here assumes "
                      "u0 = W/2 = 960 and alpha = 1 (the paper's model error), so f_p and T carry that bias.")
    console.print("projector model: " + "; ".join(projector_assumptions(calib)))
    summary = {"preset": preset, "seed": seed, "pose_deg": list(simulate.RECOMMENDED_POSE),
               "camera_f": [cam["f"], float(K[0, 0])], "projector_f": [proj["f"], float(Kp[0, 0])]}
    _files.write_text(summary_json, json.dumps(summary, indent=1))
    say(f"wrote {out_dir}/capture, {', '.join(n for n, _ in DEMO_FILES)}")
