"""``procam study``: the paper's simulation sweep of |Δf| over the board's rotation, with the CRLB."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer

from ..errors import ProcamError
from ..style import fmt_number
from ._app import app, console, err_console, fail, plain, refuse, say, user_errors
from ._options import DeviceName, ForceOpt, number, value
from ._paths import output_dir, output_path

#: Most cell-trials (cells x (trials + 1)) a study may run: about a day of one core at ~1 ms per trial.
MAX_WORK = 10**8


@app.command("study")
@user_errors
def study(
    device: DeviceName = typer.Argument(..., help="The device whose board rotation is swept."),
    output: Path = typer.Option(..., "-o", "--out", help="Output folder (CSV, JSON summary, PNG figures)."),
    grid: str = typer.Option("-45:45:5", help="Heat-map angles for both ψ and ν: START:STOP:STEP or a comma list (deg)."),
    psi_grid: Optional[str] = typer.Option(None, "--psi", help="ψ angles (deg), overrides --grid for ψ."),
    nu_grid: Optional[str] = typer.Option(None, "--nu", help="ν angles (deg), overrides --grid for ν."),
    trials: int = typer.Option(100, help="Noisy trials per cell (plus one noise-free run)."),
    noise: Optional[float] = typer.Option(None, help="Corner noise σ in px [default: 0.1 camera, 0.2 projector]."),
    model_error: str = typer.Option("paper", help="paper: pp +5 px (camera), u0p = W/2 vs 1013 (projector); none: exact."),
    distance: float = typer.Option(500.0, help="Board-centre depth on the device's optical axis (mm)."),
    slice_grid: Optional[str] = typer.Option(None, help="Angles along the paper's slices [default: the ψ grid]."),
    slices: bool = typer.Option(True, "--slices/--no-slices", help="Also run the paper's slices."),
    render: bool = typer.Option(False, help="Noisy trials from full renderings + decoding (slow, seconds per trial; "
                                            "the board must be visible to both devices: use a larger --distance)."),
    jobs: int = typer.Option(1, "-j", "--jobs", help="Worker processes (joblib; -1 = all cores; 1 = serial)."),
    dask: Optional[str] = typer.Option(None, help="Run on a Dask cluster: scheduler address, or 'local' for a LocalCluster of --jobs workers."),
    seed: int = typer.Option(0, help="Base seed (each cell and trial derives its own)."),
    figures: bool = typer.Option(True, "--figures/--no-figures", help="Write the PNG figures."),
    force: ForceOpt = False,
):
    """Sweep the board's rotation (ψ, ν) relative to a device: median |Δf| per cell and the Cramér–Rao bound.

    Reproduces the paper's simulation study and draws the single-pose Cramér–Rao bound into it.
    """
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )
    from rich.table import Table

    from ..paper.study import MODEL_ERRORS, StudyConfig, parse_grid, run_study

    device = value(device)
    if device not in ("camera", "projector"):
        raise ProcamError(f"device must be camera or projector, got {device!r}")
    number(trials, "--trials", lo=0, hi=10**6, what="a number of trials")
    number(noise, "--noise", lo=0, hi=100, unit=" px", what="a corner noise")
    if trials == 0:
        refuse(("noise",), "is the noise of the noisy trials; --trials 0 runs the noise-free one only")
    number(distance, "--distance", lo=50, hi=20000, unit=" mm", what="a board depth")
    number(seed, "--seed", lo=0, hi=2**32 - 1, what="a seed")
    if not (jobs == -1 or 1 <= jobs <= 1024):
        fail(f"-j/--jobs must be -1 (all cores) or from 1 to 1024 worker processes, got {jobs}")
    if model_error not in MODEL_ERRORS:
        fail(f"--model-error must be {' or '.join(MODEL_ERRORS)}, got {model_error!r}")
    if psi_grid is not None and nu_grid is not None:
        refuse(("grid",), "gives the angles of --psi and --nu not given; both are given")
    if not slices:
        refuse(("slice_grid",), "gives the angles of the paper's slices; --no-slices runs none")

    def angles(text, option):
        try:
            return parse_grid(text)
        except ProcamError as e:
            fail(f"{option}: {e}")

    psi = angles(psi_grid, "--psi") if psi_grid is not None else angles(grid, "--grid")
    nu = angles(nu_grid, "--nu") if nu_grid is not None else angles(grid, "--grid")
    cfg = StudyConfig(device=device, psi=psi, nu=nu, trials=trials, noise=noise, model_error=model_error,
                      distance=distance, slices=slices,
                      slice_angles=None if slice_grid is None else angles(slice_grid, "--slice-grid"), seed=seed,
                      render=render)
    from ..paper.study import study_cells

    n_cells = len(cfg.psi) * len(cfg.nu)
    if n_cells <= MAX_WORK:
        n_cells = len(study_cells(cfg))
    if n_cells * (cfg.trials + 1) > MAX_WORK:
        fail(f"the study would run {n_cells} cells x {cfg.trials + 1} calibrations (more than {MAX_WORK:.0e}, days "
             "of computing); use a coarser --grid or fewer --trials")
    output_dir(output, "-o", "study", force)
    stem = f"study_{device}_{model_error}"
    for p in sorted(output.glob(f"{stem}*")) if output.is_dir() else ():  # its files, before any work
        output_path(p, "-o", (p.suffix.lower(),))

    client = None
    backend = None
    if dask is not None:
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise ProcamError("--dask needs dask.distributed: pip install 'procam[dask]'") from None
        if dask == "local":
            n = None if jobs in (-1, 0, 1) else jobs
            client = Client(LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                         dashboard_address=None))
        else:
            client = Client(dask)
        backend = "dask"
        err_console.print(plain(f"dask: {client}"))

    total = len(study_cells(cfg))
    try:
        with Progress(TextColumn("[bold]study[/bold] {task.description}"), BarColumn(), MofNCompleteColumn(),
                      TimeElapsedColumn(), TimeRemainingColumn(), console=err_console.real, transient=True) as bar:
            tid = bar.add_task(f"{device}, model error {model_error}", total=total)
            result = run_study(cfg, n_jobs=jobs, backend=backend,
                               progress=lambda done, tot: bar.update(tid, completed=done))
    finally:
        if client is not None:
            client.close()

    output_dir(output, "-o", "study", force, create=True)
    csv_path = result.to_csv(output / f"{stem}.csv")
    # no wall times in the files: the same study writes the same bytes
    timing = ("seconds", "cells_per_second")
    summary = {"config": result.config_dict(), "summary": {k: v for k, v in result.summary().items() if k not in timing},
               "csv": csv_path.name}
    paths = []
    if figures:
        from ..plots.study import save_study_figures

        paths = save_study_figures(result, output, prefix=stem)
        summary["figures"] = [p.name for p in paths]
    from ..io import files as _files

    _files.write_text(output / f"{stem}.json", json.dumps(_files.to_jsonable(summary), indent=2))

    s = result.summary()
    console.print(f"{s['cells']} cells in {s['seconds']:.1f} s ({s['cells_per_second']:.1f} cells/s, "
                  f"{s['backend']}, {s['n_jobs']} worker(s)); σ = {cfg.sigma:g} px, {cfg.trials} trials")
    if slices:
        from ..paper.study import slice_specs

        for label, axis, fixed, val in slice_specs(cfg):
            t = Table(title=plain(f"{device}: slice {label} (|Δf| in px)"), show_lines=False)
            t.add_column(axis, justify="right")
            for name in ("median |Δf|", "noise-free |Δf|", "√CRLB", "std/√CRLB"):
                t.add_column(name, justify="right")
            for r in result.slice(label):
                t.add_row(f"{r[axis]:g}", *(fmt_number(r[k], spec=".3g")
                                            for k in ("median_abs_df", "abs_df_noise_free", "bound_f", "ratio_std")))
            console.print(t)
    say(f"wrote {csv_path}" + (f" and {len(paths)} figures" if paths else "") + f" to {output}")
