"""The paper's simulation study: |Δf| over the board's rotation (ψ, ν) relative to a device.

Reproduces Lawal & Greenspan's simulation sweeps (their Figs 4–7) and adds, per cell, the
Cramér–Rao bound of the same single-pose problem (:mod:`procam.crlb`), i.e. what any unbiased
method could achieve at that pose with that noise.

Set-up (the paper's, with procam's choices where it is silent: the square size, the distance, the
noise): the ``paper`` preset of :mod:`procam.simulate` without camera lens distortion; the board
(10 × 6 corners at 24 mm) centred on the device's optical axis at ``distance`` (500 mm), rotated
about its centre by ``Rx(ψ) Ry(ν)`` with φ = 0, in the frame of the studied device.  Per cell and
trial, noisy correspondences from the exact geometry (:func:`procam.simulate.correspondences`) are
calibrated by the single-pose method (:mod:`procam.single_pose`), and the median |Δf| over the
trials is recorded together with a noise-free run (the deterministic bias) and the bound.

Model errors (``model_error``):

``"paper"``
    The paper's deliberate ones: the camera's principal point is fixed at truth + ``pp_offset``
    ((+5, +5) px, emulating a COD error); the projector is calibrated with ``u0 = W/2`` = 960 and
    ``α = 1`` against a truth of 1013 and 1.002.
``"none"``
    The camera's principal point is fixed at the truth; the projector is calibrated with the true
    ``u0`` and the scene's projector has ``α = 1`` (the value the method assumes), so with noise
    the estimator can only be limited by the noise: its spread is to be compared with the bound.

Parallelism: cells are independent and seeded from ``(seed, device, ψ, ν, trial)``, so a study gives
the same numbers serially, with joblib processes or on a Dask cluster (joblib's ``dask`` backend;
:mod:`procam.paper._parallel`).  joblib is an optional dependency (``procam[parallel]``); the serial
path does not need it.
"""

from __future__ import annotations

import csv
import math
import time
from functools import lru_cache, partial
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Iterable, Sequence

import numpy as np

from ..io.files import atomic_path
from ..crlb import camera_bound, projector_bound
from ..errors import ProcamError
from ._parallel import run_chunks, single_threaded_blas

__all__ = ["StudyConfig", "StudyResult", "parse_grid", "study_cells", "study_scene", "cell_scene",
           "run_cell", "run_study", "slice_specs", "COLUMNS"]

DEVICES = ("camera", "projector")
MODEL_ERRORS = ("paper", "none")

#: Default corner noise per device (px, per coordinate; the paper does not give its noise level).
DEFAULT_NOISE = {"camera": 0.1, "projector": 0.2}

#: The paper's slices (its Figs 5 and 7): (varying axis, fixed axis, fixed value in degrees).
SLICES = {
    "camera": (("psi", "nu", 10.0), ("nu", "psi", 10.0)),
    "projector": (("nu", "psi", 10.0), ("psi", "nu", 3.5), ("psi", "nu", -3.5)),
}

#: CSV columns, in order (one row per cell).  A row's wall time ("seconds") is not written, so the same study
#: writes the same bytes.
COLUMNS = ("device", "model_error", "psi", "nu", "in_grid", "slices", "trials", "noise", "n_ok",
           "f_true", "f_median", "median_abs_df", "mean_df", "std_f", "df_noise_free",
           "abs_df_noise_free", "bound_f", "bound_f_per_px", "ratio_median", "ratio_std")


#: Most angles a grid axis may have (a 1000 x 1000 heat map is already a million cells).
MAX_GRID = 1000


def parse_grid(text: str) -> np.ndarray:
    """Angles from ``"start:stop:step"`` (stop included) or a comma list ``"-10,0,10"`` (degrees).

    >>> parse_grid("-10:10:5").tolist()
    [-10.0, -5.0, 0.0, 5.0, 10.0]
    >>> parse_grid("3.5,-3.5").tolist()
    [-3.5, 3.5]
    """
    try:
        if ":" in text:
            parts = [float(p) for p in text.split(":")]
            if len(parts) != 3 or not all(math.isfinite(v) for v in parts) or parts[2] <= 0 or parts[1] < parts[0]:
                raise ValueError
            start, stop, step = parts
            n = (stop - start) / step + 1e-9
            if n >= MAX_GRID:
                raise ProcamError(f"grid {text!r} has {n:.3g} angles; at most {MAX_GRID} per axis (use a larger "
                                  "STEP)")
            vals = start + step * np.arange(int(math.floor(n)) + 1)
        else:
            vals = np.array([float(p) for p in text.split(",") if p.strip()])
            if vals.size == 0 or not np.all(np.isfinite(vals)):
                raise ValueError
            if vals.size > MAX_GRID:
                raise ProcamError(f"grid has {vals.size} angles; at most {MAX_GRID} per axis")
    except ValueError:
        raise ProcamError(f"grid must be START:STOP:STEP (e.g. -45:45:5) or a comma list of finite angles in "
                          f"degrees, got {text!r}") from None
    if np.any(np.abs(vals) >= 89.0):      # before rounding: an angle of 1e300 would overflow it
        raise ProcamError(f"grid angles must lie within (-89, 89) degrees, got {text!r}")
    vals = np.unique(np.round(vals, 9))
    return vals


@dataclass(frozen=True)
class StudyConfig:
    """What to sweep and how (angles in degrees, lengths in mm, noise in px).

    Parameters
    ----------
    device : ``"camera"`` or ``"projector"``.
    psi, nu : grid of the heat map (degrees).
    trials : noisy trials per cell (the noise-free run is extra).
    noise : corner noise of the studied device (px); ``None`` = 0.1 camera / 0.2 projector.
    model_error : ``"paper"`` or ``"none"`` (module docstring).
    distance : depth of the board centre on the device's optical axis (mm).
    pp_offset : camera principal-point error of the ``paper`` model error (px).
    slices : also run the paper's slices (:data:`SLICES`) over ``slice_angles``.
    slice_angles : angles along the slices; ``None`` = ``psi``.
    seed : base seed.
    preset : :func:`procam.simulate.preset` name.
    render : noisy trials from full renderings (:func:`procam.simulate.render`, the scene's
        photometric noise) decoded by :func:`procam.pipeline.view_from_stack`, instead of exact
        corners plus Gaussian noise; slow (seconds per trial).  ``noise`` then only sets the
        bound's σ.  The noise-free run stays on the exact corners.  The board must be seen by both
        devices (the pipeline needs projector corners): with the paper rig that needs
        ``distance`` > 500 mm; trials whose capture cannot be processed count as failed (``n_ok``).
    """

    device: str = "camera"
    psi: tuple = tuple(np.arange(-45.0, 45.1, 5.0))
    nu: tuple = tuple(np.arange(-45.0, 45.1, 5.0))
    trials: int = 100
    noise: float | None = None
    model_error: str = "paper"
    distance: float = 500.0
    pp_offset: tuple = (5.0, 5.0)
    slices: bool = True
    slice_angles: tuple | None = None
    seed: int = 0
    preset: str = "paper"
    render: bool = False

    def __post_init__(self):
        s = object.__setattr__
        if self.device not in DEVICES:
            raise ProcamError(f"device must be camera or projector, got {self.device!r}")
        if self.model_error not in MODEL_ERRORS:
            raise ProcamError(f"model error must be paper or none, got {self.model_error!r}")
        if int(self.trials) < 0:
            raise ProcamError(f"trials must be >= 0, got {self.trials}")
        s(self, "trials", int(self.trials))
        s(self, "psi", tuple(float(a) for a in np.atleast_1d(self.psi)))
        s(self, "nu", tuple(float(a) for a in np.atleast_1d(self.nu)))
        if self.slice_angles is not None:
            s(self, "slice_angles", tuple(float(a) for a in np.atleast_1d(self.slice_angles)))
        s(self, "pp_offset", (float(self.pp_offset[0]), float(self.pp_offset[1])))
        if self.noise is not None and not (math.isfinite(self.noise) and self.noise >= 0):
            raise ProcamError(f"noise must be a finite number >= 0 px, got {self.noise}")
        if not (math.isfinite(self.distance) and self.distance > 0):
            raise ProcamError(f"distance must be a finite positive depth in mm, got {self.distance}")
        for name in ("psi", "nu", "slice_angles"):
            v = getattr(self, name)
            if v is not None and not (len(v) and all(math.isfinite(a) and abs(a) < 89.0 for a in v)):
                raise ProcamError(f"{name} angles must be finite and within (-89, 89) degrees, got {v}")

    @property
    def sigma(self) -> float:
        """Corner noise (px) of the studied device."""
        return DEFAULT_NOISE[self.device] if self.noise is None else float(self.noise)


def slice_specs(config: StudyConfig):
    """The slices of ``config.device``: list of ``(label, axis, fixed_axis, fixed_value)``."""
    return [(f"{fixed}={val:g}", axis, fixed, val) for axis, fixed, val in SLICES[config.device]]


def study_cells(config: StudyConfig) -> list[tuple[float, float, bool, str]]:
    """All cells to run: ``(psi, nu, in_grid, slice_labels)``, the grid first, duplicates merged.

    ``slice_labels`` is a ``;``-separated list of the slices a cell belongs to (``"nu=10"``).
    """
    cells: dict[tuple[float, float], list] = {}
    for p in config.psi:
        for n in config.nu:
            cells[(round(p, 9), round(n, 9))] = [True, []]
    if config.slices:
        along = config.psi if config.slice_angles is None else config.slice_angles
        for label, axis, _fixed, val in slice_specs(config):
            for a in along:
                key = (round(a, 9), round(val, 9)) if axis == "psi" else (round(val, 9), round(a, 9))
                cells.setdefault(key, [False, []])[1].append(label)
    return [(k[0], k[1], v[0], ";".join(v[1])) for k, v in cells.items()]


@lru_cache(maxsize=8)
def _preset(name: str):
    # simulate.preset() places its board by optimisation (~1 s); the scene is immutable, so cache it
    from .. import simulate

    return simulate.preset(name)


def study_scene(config: StudyConfig):
    """The base :class:`procam.simulate.Scene` of a study (truth adjusted for ``model_error``)."""
    scene = _preset(config.preset)
    scene = scene.replace(cam_distortion="none", cam_dist_coeffs=(), name=f"study-{config.preset}")
    if config.model_error == "none":
        Kp = np.array(scene.K_proj, float)
        Kp[1, 1] = Kp[0, 0]  # alpha_p = 1, as the method assumes
        scene = scene.replace(K_proj=Kp)
    return scene


def cell_scene(config: StudyConfig, psi: float, nu: float, base=None):
    """The study scene with the board at ``(psi, nu, 0)`` centred at ``(0, 0, distance)`` in the
    studied device's frame (the paper's simulation set-up)."""
    from .. import simulate

    base = study_scene(config) if base is None else base
    return simulate.with_board_pose(base, (psi, nu, 0.0), frame=config.device,
                                    center=(0.0, 0.0, config.distance))


def _trial_seed(config: StudyConfig, psi: float, nu: float, trial: int) -> int:
    key = [int(config.seed), DEVICES.index(config.device), int(round(psi * 1000)) + 10 ** 6,
           int(round(nu * 1000)) + 10 ** 6, int(trial)]
    return int(np.random.SeedSequence(key).generate_state(1)[0])


def _calibrate_f(config: StudyConfig, scene, obj, pts) -> float:
    """Single-pose focal length of the studied device (NaN if the method fails)."""
    from .. import single_pose

    try:
        if config.device == "camera":
            pp = np.array(scene.K_cam[:2, 2], float)
            if config.model_error == "paper":
                pp = pp + np.array(config.pp_offset)
            sol = single_pose.calibrate_camera(
                obj, pts, scene.cam_size, single_pose.CameraOptions(principal_point=(pp[0], pp[1]), distortion=None))
        else:
            u0 = None if config.model_error == "paper" else float(scene.K_proj[0, 2])
            sol = single_pose.calibrate_projector(obj, pts, scene.proj_size, single_pose.ProjectorOptions(u0=u0))
        f = float(np.asarray(sol.K)[0, 0])
    except (ProcamError, np.linalg.LinAlgError, ValueError, FloatingPointError):
        return float("nan")
    return f if np.isfinite(f) and f > 0 else float("nan")


def _points(config: StudyConfig, scene, sigma: float, seed: int, render: bool = False):
    from .. import simulate

    if render:
        return _rendered_points(config, scene, seed)
    if config.device == "camera":
        obj, cam, _ = simulate.correspondences(scene, sigma, 0.0, seed)
        return obj, cam
    obj, _, proj = simulate.correspondences(scene, 0.0, sigma, seed)
    return obj, proj


def _rendered_points(config: StudyConfig, scene, seed: int):
    """Corners from a full rendering: render -> decode -> detect -> local homographies (NaN rows if lost)."""
    from .. import patterns, pipeline, simulate
    from ..board import Board

    stack, _ = simulate.render(scene, order="opencv", seed=seed)
    ps = patterns.pattern_set(scene.proj_size[0], scene.proj_size[1], "opencv")
    try:
        view, _ = pipeline.view_from_stack(stack, ps, Board(scene.board_cols, scene.board_rows, scene.square),
                                           name=f"study cell seed {seed}")
    except ProcamError:
        n = scene.board_cols * scene.board_rows
        return simulate.board_corners(scene), np.full((n, 2), np.nan)
    pts = view.cam_pts if config.device == "camera" else view.proj_pts
    return np.asarray(view.obj_pts, float), np.asarray(pts, float)


def _bound(config: StudyConfig, scene, obj, sigma: float) -> float:
    """√CRLB(f) of the studied device's single-pose problem at the cell (px)."""
    if config.device == "camera":
        b = camera_bound(scene.K_cam, None, 0.0, 0.0, scene.R_board, scene.t_board, obj, sigma,
                         model="known_distortion")
    else:
        b = projector_bound(scene.K_proj, scene.R_board_proj, scene.t_board_proj, obj, sigma)
    return float(b.std["f_c" if config.device == "camera" else "f_p"])


def run_cell(config: StudyConfig, psi: float, nu: float, in_grid: bool = True, slices: str = "",
             base=None) -> dict:
    """Run one cell: a noise-free calibration, ``config.trials`` noisy ones and the bound.

    Returns
    -------
    dict
        One CSV row (:data:`COLUMNS`): ``f_true`` (px), ``median_abs_df`` = median |f̂ − f| over the
        successful trials, ``mean_df`` (bias), ``std_f`` (ddof 1), ``df_noise_free`` (signed),
        ``bound_f`` = √CRLB(f) at ``config.sigma`` and ``bound_f_per_px`` at σ = 1 px, ratios
        ``median_abs_df / bound_f`` and ``std_f / bound_f`` (an efficient unbiased estimator
        gives ≈ 0.674 and 1), ``n_ok`` successful trials; NaN where undefined.
    """
    with single_threaded_blas():
        return _run_cell(config, psi, nu, in_grid, slices, base)


def _run_cell(config, psi, nu, in_grid, slices, base):
    t0 = time.perf_counter()
    scene = cell_scene(config, psi, nu, base)
    f_true = float(scene.K_cam[0, 0] if config.device == "camera" else scene.K_proj[0, 0])
    sigma = config.sigma
    obj, exact = _points(config, scene, 0.0, 0)
    df0 = _calibrate_f(config, scene, obj, exact) - f_true
    fs = np.array([_calibrate_f(config, scene, *_points(config, scene, sigma, _trial_seed(config, psi, nu, k),
                                                        config.render))
                   for k in range(config.trials)], float)
    ok = fs[np.isfinite(fs)]
    per_px = _bound(config, scene, obj, 1.0)
    bound = per_px * sigma
    nan = float("nan")
    med = float(np.median(np.abs(ok - f_true))) if ok.size else nan
    std = float(np.std(ok, ddof=1)) if ok.size > 1 else nan
    with np.errstate(divide="ignore", invalid="ignore"):
        r_med = med / bound if bound > 0 and np.isfinite(bound) else nan
        r_std = std / bound if bound > 0 and np.isfinite(bound) else nan
    return {"device": config.device, "model_error": config.model_error, "psi": float(psi), "nu": float(nu),
            "in_grid": bool(in_grid), "slices": slices, "trials": config.trials, "noise": sigma,
            "n_ok": int(ok.size), "f_true": f_true,
            "f_median": float(np.median(ok)) if ok.size else nan, "median_abs_df": med,
            "mean_df": float(np.mean(ok) - f_true) if ok.size else nan, "std_f": std,
            "df_noise_free": float(df0), "abs_df_noise_free": float(abs(df0)),
            "bound_f": float(bound), "bound_f_per_px": float(per_px),
            "ratio_median": float(r_med), "ratio_std": float(r_std),
            "seconds": time.perf_counter() - t0}


def _run_chunk(config: StudyConfig, cells: Sequence[tuple]) -> list[dict]:
    base = study_scene(config)
    return [run_cell(config, p, n, g, s, base=base) for p, n, g, s in cells]


def run_study(config: StudyConfig, *, n_jobs: int = 1, backend: str | None = None,
              chunk_size: int | None = None, progress: Callable[[int, int], None] | None = None,
              cells: Iterable[tuple] | None = None) -> "StudyResult":
    """Run every cell of ``config`` (the grid, then the slices).

    Parameters
    ----------
    n_jobs : worker count for joblib (``1`` = serial, no joblib needed; ``-1`` = all cores).
    backend : joblib backend: ``None`` (``"loky"`` processes when ``n_jobs != 1``) or ``"dask"`` —
        the latter needs a ``dask.distributed.Client`` connected in this process (see
        ``procam study``, option ``--dask``); the work then runs on that cluster.
    chunk_size : cells per task (default: about 4 tasks per worker, at most 16 cells).
    progress : called as ``progress(cells_done, cells_total)`` after each finished chunk.
    cells : override :func:`study_cells` (tuples ``(psi, nu, in_grid, slices)``).

    Returns
    -------
    StudyResult
        Rows in the order of ``cells``, whatever the order the workers finished in.

    Examples
    --------
    Serially, with local processes, or on a Dask cluster (``pip install 'procam[dask]'``; every
    worker needs procam installed); all three give identical rows::

        cfg = StudyConfig("projector", psi=parse_grid("-45:45:5"), nu=parse_grid("-45:45:5"))
        res = run_study(cfg)                      # serial, no joblib needed
        res = run_study(cfg, n_jobs=-1)           # joblib/loky processes on this machine
        from dask.distributed import Client
        with Client("tcp://scheduler:8786"):      # or Client(LocalCluster(...))
            res = run_study(cfg, backend="dask")  # joblib's dask backend: tasks run on the cluster
        res.to_csv("study.csv")

    The CLI does the same with ``procam study projector -j 2`` or ``--dask tcp://scheduler:8786``
    (``--dask local`` starts a LocalCluster of ``--jobs`` workers).
    """
    todo = list(study_cells(config) if cells is None else cells)
    total = len(todo)
    t0 = time.perf_counter()
    rows: list[dict] = []
    if n_jobs == 1 and backend is None:
        base = study_scene(config)
        for i, (p, n, g, s) in enumerate(todo):
            rows.append(run_cell(config, p, n, g, s, base=base))
            if progress is not None:
                progress(i + 1, total)
        return StudyResult(config, rows, time.perf_counter() - t0, {"n_jobs": 1, "backend": "serial"})
    rows, run = run_chunks(partial(_run_chunk, config), todo, n_jobs=n_jobs, backend=backend,
                           chunk_size=chunk_size, progress=progress)
    return StudyResult(config, rows, time.perf_counter() - t0, run)


@dataclass
class StudyResult:
    """Rows of a study (one dict per cell, :data:`COLUMNS`) with its configuration.

    Attributes
    ----------
    config : StudyConfig
    rows : list of dict
    seconds : wall-clock time of :func:`run_study`.
    run : how it ran (``n_jobs``, ``backend``, ``chunk_size``).
    """

    config: StudyConfig
    rows: list
    seconds: float = 0.0
    run: dict = field(default_factory=dict)

    def column(self, name: str, rows=None) -> np.ndarray:
        rows = self.rows if rows is None else rows
        return np.array([r[name] for r in rows])

    def grid(self, name: str = "median_abs_df") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(psi (P,), nu (Q,), values (P, Q))`` of a column over the heat-map grid (NaN if absent)."""
        psi, nu = np.array(self.config.psi), np.array(self.config.nu)
        val = np.full((psi.size, nu.size), np.nan)
        ip = {round(p, 9): i for i, p in enumerate(psi)}
        iq = {round(n, 9): j for j, n in enumerate(nu)}
        for r in self.rows:
            i, j = ip.get(round(r["psi"], 9)), iq.get(round(r["nu"], 9))
            if i is not None and j is not None:
                val[i, j] = r[name]
        return psi, nu, val

    def slice_specs(self) -> list[tuple[str, str, str, float]]:
        """The study's slices: ``(label, axis, fixed_axis, fixed_value)`` each (see :func:`slice_specs`)."""
        return slice_specs(self.config)

    def slice(self, label: str) -> list[dict]:
        """Rows of one slice (``"nu=10"``), sorted along the varying axis."""
        spec = {s[0]: s for s in slice_specs(self.config)}.get(label)
        if spec is None:
            raise KeyError(f"no slice {label!r}; have {[s[0] for s in slice_specs(self.config)]}")
        _, axis, fixed, val = spec
        rows = [r for r in self.rows if abs(r[fixed] - val) < 1e-9 and label in r["slices"].split(";")]
        if not rows:  # slices not run: take what the grid has on that line
            rows = [r for r in self.rows if abs(r[fixed] - val) < 1e-9]
        return sorted(rows, key=lambda r: r[axis])

    def to_csv(self, path) -> Path:
        """Write every cell as a CSV row (:data:`COLUMNS`), atomically; returns the path."""
        path = Path(path)
        with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(COLUMNS))
            w.writeheader()
            for r in self.rows:
                w.writerow({k: (f"{r[k]:.6g}" if isinstance(r[k], float) else r[k]) for k in COLUMNS})
        return path

    @classmethod
    def from_csv(cls, path, config: StudyConfig) -> "StudyResult":
        """Read rows written by :meth:`to_csv` (for re-plotting)."""
        rows = []
        with Path(path).open() as fh:
            for r in csv.DictReader(fh):
                out = {}
                for k in COLUMNS:
                    v = r[k]
                    if k in ("device", "model_error", "slices"):
                        out[k] = v
                    elif k == "in_grid":
                        out[k] = v == "True"
                    elif k in ("trials", "n_ok"):
                        out[k] = int(v)
                    else:
                        out[k] = float(v)
                rows.append(out)
        return cls(config, rows)

    def summary(self) -> dict:
        """Key numbers: cells, time, cells/s, median ratios over finite-bound cells."""
        ok = [r for r in self.rows if np.isfinite(r["ratio_median"])]
        stds = [r["ratio_std"] for r in ok if np.isfinite(r["ratio_std"])]  # none with one trial per cell
        return {"cells": len(self.rows), "seconds": self.seconds,
                "cells_per_second": len(self.rows) / self.seconds if self.seconds > 0 else float("nan"),
                "median_ratio_median": float(np.median([r["ratio_median"] for r in ok])) if ok else float("nan"),
                "median_ratio_std": float(np.median(stds)) if stds else float("nan"),
                **self.run}

    def config_dict(self) -> dict:
        return asdict(self.config)
