"""``procam simulate``: render a synthetic capture folder with ground truth."""

from __future__ import annotations

from pathlib import Path

import typer

from ..patterns import ORDERS
from ._app import app, console, fail, is_tty, user_errors


def _parse_pose(text: str) -> tuple[float, float, float]:
    parts = [p for p in text.replace(";", ",").split(",") if p.strip()] if text else []
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        vals = []
    if len(vals) not in (2, 3):
        fail(f"--pose must be PSI,NU[,PHI] in degrees (e.g. 15,12,0), got {text!r}")
    if len(vals) == 2:
        vals.append(0.0)
    if any(abs(v) >= 80 for v in vals[:2]):
        fail(f"--pose angles psi and nu must be within +-80 degrees, got {text!r}")
    return vals[0], vals[1], vals[2]


@app.command("simulate")
@user_errors
def simulate_cmd(
    out_dir: Path = typer.Argument(..., help="Output folder for the images, truth.json and patterns.json."),
    preset: str = typer.Option("paper", "--preset", help="Rig: paper (the paper's simulated procam) or ideal "
                               "(u0p = W/2, alpha_p = 1, stronger lens distortion)."),
    pose: str = typer.Option(None, "--pose", help="Board angles PSI,NU,PHI in degrees (XYZ Euler, board -> "
                             "device; default: the recommended pose)."),
    frame: str = typer.Option("camera", "--frame", help="Device frame of --pose: camera or projector."),
    distance: float = typer.Option(None, "--distance", help="Board-centre depth in mm along the device's axis "
                                   "(default: the nearest that keeps the whole board in both images)."),
    noise: float = typer.Option(None, "--noise", help="Camera read noise in 8-bit DN (default 1.0); 0 renders "
                                "without any noise (no shot noise either)."),
    bits: int = typer.Option(8, "--bits", help="Output bit depth: 8 or 16."),
    seed: int = typer.Option(0, "--seed", help="Noise seed (same seed -> identical images)."),
    order: str = typer.Option("opencv", "--order", help="Sequence order: opencv (default) or moreno."),
):
    """Render a synthetic Gray-code capture of a chessboard, with its ground truth (truth.json)."""
    from .. import simulate as sim

    if preset not in sim.PRESETS:
        fail(f"--preset must be one of {', '.join(sim.PRESETS)}, got {preset!r}")
    if bits not in (8, 16):
        fail(f"--bits must be 8 or 16, got {bits}")
    if order not in ORDERS:
        fail(f"--order must be one of {', '.join(ORDERS)}, got {order!r}")
    if frame not in ("camera", "projector"):
        fail(f"--frame must be camera or projector, got {frame!r}")
    if distance is not None and not (50 <= distance <= 20000):
        fail(f"--distance must be between 50 and 20000 mm, got {distance}")
    if noise is not None and noise < 0:
        fail(f"--noise must be >= 0 DN, got {noise}")
    angles = _parse_pose(pose) if pose else sim.RECOMMENDED_POSE

    scene = sim.preset(preset)
    if pose is not None or distance is not None or frame != "camera":
        scene = sim.with_board_pose(scene, angles, distance=distance, frame=frame)
    changes = {"bits": bits}
    if noise is not None:
        changes["read_noise"] = noise
        if noise == 0:
            changes["full_well"] = 0.0
    scene = scene.replace(**changes)
    margin = sim.fit_margin(scene)

    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(TextColumn("[progress.description]{task.description}"), BarColumn(),
                  TextColumn("{task.completed}/{task.total}"), TimeElapsedColumn(),
                  console=console, transient=True, disable=not is_tty()) as bar:
        task = bar.add_task("rendering", total=1)

        def progress(done, total):
            bar.update(task, completed=done, total=total)

        stack, truth = sim.render(scene, order=order, seed=seed, progress=progress)
        bar.update(task, description="writing")
        paths = sim.write_capture(out_dir, stack, truth, order=order)

    pc, pp = truth["pose"]["camera"], truth["pose"]["projector"]
    console.print(f"wrote {len(paths)} images ({stack.shape[2]}x{stack.shape[1]}, {bits}-bit, order {order}), "
                  f"truth.json and patterns.json to {out_dir}")
    console.print(f"preset {preset}; board (psi, nu, phi) camera ({pc['angles_deg'][0]:.2f}, "
                  f"{pc['angles_deg'][1]:.2f}, {pc['angles_deg'][2]:.2f}) deg, projector ({pp['angles_deg'][0]:.2f}, "
                  f"{pp['angles_deg'][1]:.2f}, {pp['angles_deg'][2]:.2f}) deg; centre "
                  f"({pc['t'][0]:.1f}, {pc['t'][1]:.1f}, {pc['t'][2]:.1f}) mm in the camera frame", highlight=False)
    if margin < 0:
        console.print(f"[yellow]warning:[/yellow] part of the board (with its margin) is outside the camera or "
                      f"projector image ({margin:.0f} px); some corners may be missing — try a larger --distance "
                      "or smaller angles", highlight=False)
