"""What the poses themselves say about a multi-pose calibration: the leave-one-pose-out spread of its parameters.

The fit's ``±`` (its Jacobian at the solution) assumes the model is right, the corner noise independent and the
problem well posed. A set that does not determine a parameter violates the last: the Jacobian still gives a
small ``±`` at whatever point the optimiser stopped. The poses themselves tell: refit without each pose in
turn (same options; from the calibration's own solution where the other poses determine the parameters, else from
scratch: :func:`refit_each`) and look at how far each parameter moves. The jackknife standard error over the ``n``
refits, ``sqrt((n - 1) / n * sum (x_i - mean)^2)``, estimates the parameter's uncertainty with no model of the
noise; for a sound set it is close to the fit's ``±`` (within about 3x on the simulator's sets of 4-7 poses),
for a set that rests on one pose it is hundreds of times larger.

:func:`parameter_spread` computes it, :func:`judge_spread` turns it into words and a level:

* **degenerate** (not determined): a parameter's spread over 10 % of its scale (the focal length for
  ``f``, the image width / height for the principal point, ``|T|`` for ``T``), and more than 3x the fit's
  ``±`` where there is one; a refit that finds no calibration at all without pose ``i`` means every parameter
  rests on that pose;
* **weak**: the spread over 4x the fit's ``±`` (and over 0.5 % of the scale): the ``±`` is optimistic; or,
  with no fit ``±`` (no joint refinement), a spread over 2 % of the scale.

The message names each parameter, its spread against its ``±``, and the pose whose removal moves it most (the
one the calibration rests on). Needs at least 4 poses (3 left in every refit): with fewer there is no
evidence, which the caller says.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ProcamError

__all__ = ["SpreadOptions", "parameter_spread", "judge_spread", "refit_each", "determined", "MIN_POSES"]

#: Fewest poses for a leave-one-pose-out spread (every refit keeps 3).
MIN_POSES = 4

#: The parameters whose spread is judged, and the devices they belong to.
PARAMS = ("f_c", "fy_c", "u0c", "v0c", "f_p", "fy_p", "u0p", "v0p", "T[0]", "T[1]", "T[2]")


@dataclass(frozen=True)
class SpreadOptions:
    """Thresholds of :func:`judge_spread` (module docstring)."""

    degenerate_rel: float = 0.10
    degenerate_ratio: float = 3.0
    weak_ratio: float = 4.0
    weak_rel_floor: float = 0.005
    weak_rel_without_std: float = 0.02
    #: a warm-started leave-one-out refit stands in for one from scratch where its own ``±`` is within this
    #: fraction of every judged parameter's scale (:func:`determined`)
    warm_rel: float = 0.02


def _params(c) -> dict:
    Kc, Kp = c.camera.K, c.projector.K
    out = {"f_c": Kc[0, 0], "fy_c": Kc[1, 1], "u0c": Kc[0, 2], "v0c": Kc[1, 2], "f_p": Kp[0, 0], "fy_p": Kp[1, 1],
           "u0p": Kp[0, 2], "v0p": Kp[1, 2]}
    out.update({f"T[{i}]": float(c.T[i]) for i in range(3)})
    return {k: float(v) for k, v in out.items()}


def parameter_spread(calib, refits) -> dict:
    """The spread of the leave-one-out refits' parameters next to the calibration's own ± (Jacobian std).

    Returns ``{name: (value, jacobian_std, refit_std)}`` for the intrinsics and ``T`` (named as in
    :mod:`procam.parameters`). ``refit_std`` is the jackknife standard error
    ``sqrt((n - 1) / n * sum (x_i - mean)^2)`` over the ``n`` refits: what the data say the parameter's
    uncertainty is, with no model of the noise; a Jacobian std much smaller than it means the ± is
    optimistic (correlated or non-Gaussian corner errors, a model that does not fit, a set that does not
    determine the parameter). Refits that are not calibrations (failures) are skipped; fewer than 2 give ``{}``.
    """
    refits = [r for r in refits if not isinstance(r, BaseException) and r is not None]
    n = len(refits)
    if n < 2:
        return {}
    base = _params(calib)
    sets = [_params(r) for r in refits]
    out = {}
    for k, v in base.items():
        xs = np.array([p[k] for p in sets], float)
        jack = float(np.sqrt((n - 1) / n * np.sum((xs - xs.mean()) ** 2)))
        js = _fit_std(calib, k)
        out[k] = (float(v), None if js is None else float(js), jack)
    return out


def _fit_std(calib, k):
    """The ``±`` the fit gives parameter ``k`` of :data:`PARAMS` (``T[i]`` from ``std["T"]``), or None."""
    if k.startswith("T["):
        t = calib.std.get("T")
        return t[int(k[2])] if t is not None else None
    return calib.std.get(k)


def _scale(calib, k) -> float:
    if k.startswith("T["):
        return float(np.linalg.norm(calib.T))
    dev = calib.camera if k in ("f_c", "fy_c", "u0c", "v0c") else calib.projector
    W, H = dev.image_size
    if k.startswith("u0"):
        return float(W)
    if k.startswith("v0"):
        return float(H)
    return abs(float(dev.K[0, 0] if k.startswith("f_") else dev.K[1, 1]))


def _short(name) -> str:
    return Path(str(name)).name or str(name)


def judge_spread(calib, refits, names, options: SpreadOptions = SpreadOptions()) -> tuple[str, list[str], dict]:
    """The verdict the leave-one-pose-out refits give (module docstring): ``(level, reasons, details)``.

    Parameters
    ----------
    calib : the calibration from all poses.
    refits : one entry per pose, in the poses' order: the calibration without that pose, or the
        :class:`~procam.errors.ProcamError` its refit raised.
    names : the poses' names.

    Returns
    -------
    level ``"good"``, ``"weak"`` or ``"degenerate"``; reasons (one line each); details ``{"spread": {name:
    [value, fit std or None, spread]}, "moved_most_by": {name: pose}, "failed_refits": {pose: message}}`` for the
    file.
    """
    names = [_short(n) for n in names]
    failed = {n: str(r) for n, r in zip(names, refits) if isinstance(r, BaseException)}
    ok = [(n, r) for n, r in zip(names, refits) if not isinstance(r, BaseException) and r is not None]
    spread = parameter_spread(calib, [r for _, r in ok])
    base = _params(calib)
    details = {"spread": {k: [v, js, jack] for k, (v, js, jack) in spread.items()}, "moved_most_by": {},
               "failed_refits": failed}
    level, reasons = "good", []
    if failed:
        level = "degenerate"
        for n, m in failed.items():
            reasons.append(f"without pose {n!r} the other poses determine no calibration ({m}): every parameter "
                           "rests on that one pose, so none is determined; capture more poses like it (tilted "
                           "15-30 deg about different axes)")
    undetermined, optimistic = [], []
    for k, (v, js, jack) in spread.items():
        scale = _scale(calib, k)
        if not (scale > 0 and np.isfinite(jack)):
            continue
        rel = jack / scale
        ratio = jack / js if js else None
        far = max(ok, key=lambda nr: abs(_params(nr[1])[k] - base[k]))
        details["moved_most_by"][k] = far[0]
        if rel > options.degenerate_rel and (ratio is None or ratio > options.degenerate_ratio):
            undetermined.append((k, v, js, jack, far))
        elif ratio is not None and ratio > options.weak_ratio and rel > options.weak_rel_floor:
            optimistic.append((k, v, js, jack))
        elif ratio is None and rel > options.weak_rel_without_std:
            optimistic.append((k, v, js, jack))

    if undetermined:
        level = "degenerate"
        k, v, js, jack, (pose, refit) = undetermined[0]
        poses = sorted({u[4][0] for u in undetermined})
        reasons.insert(0, f"not determined by these poses: leaving one pose out moves {_spreads(undetermined)}; "
                       f"without pose {pose!r} {k} is {_params(refit)[k]:.4g} instead of {v:.4g}: the calibration "
                       f"rests on pose{'s' if len(poses) > 1 else ''} {', '.join(repr(p) for p in poses)}; capture "
                       "more poses tilted 15-30 deg about different axes")
    elif optimistic:
        level = "weak" if level == "good" else level
        reasons.append(f"the ± is optimistic: leaving one pose out moves {_spreads(optimistic)}: the poses disagree "
                       "more than the corner noise explains (a model that does not fit, correlated corner errors, or "
                       "a pose unlike the rest)")
    return level, reasons, details


def _spreads(items) -> str:
    """``"f_c by ±889 (82 times its ±11 from the fit), fy_c by ±691 (63 times)"``; without fit ± said once."""
    parts, no_std = [], False
    for n, (k, v, js, jack, *_) in enumerate(items):
        u = "" if k.startswith("T[") else " px"
        if js:
            parts.append(f"{k} by ±{jack:.3g}{u} ({jack / js:.0f} times its ±{js:.2g} from the fit)" if n == 0 else
                         f"{k} by ±{jack:.3g}{u} ({jack / js:.0f} times)")
        else:
            parts.append(f"{k} by ±{jack:.3g}{u}")
            no_std = True
    return ", ".join(parts) + (" (no ± from the fit without the joint refinement)" if no_std else "")


def refit_each(views, calibrate, warm=None, **options) -> list:
    """``calibrate(views without pose i, **options)`` for every pose ``i`` (two at a time); an entry is the refit's
    :class:`ProcamError` where it raised.

    ``warm(i)``, when given, is the refit without pose ``i`` started from the calibration of all the poses
    (:func:`procam.multi_pose.refit_without`: a few steps of the joint refinement instead of a calibration from
    scratch). It stands in for the refit where its own ``±`` says the other poses determine every judged parameter
    (:func:`determined`); elsewhere, or where it diverges, the refit starts from scratch: where a warm start stops
    along what the other poses leave free says little, and it would hide the very spread the verdict looks for.
    """
    from concurrent.futures import ThreadPoolExecutor
    import warnings

    from ..errors import ProcamWarning

    views = list(views)

    def one(i):
        if warm is not None:
            try:
                refit = warm(i)
            except ProcamError:
                refit = None
            if refit is not None and determined(refit):
                return refit
        try:
            return calibrate(views[:i] + views[i + 1:], **options)
        except ProcamError as e:
            return e

    with warnings.catch_warnings():  # a refit's warnings are the full calibration's, minus a pose
        warnings.simplefilter("ignore", ProcamWarning)
        with ThreadPoolExecutor(2) as ex:
            return list(ex.map(one, range(len(views))))


def determined(calib, options: SpreadOptions = SpreadOptions()) -> bool:
    """Whether ``calib``'s own ``±`` (its fit's Jacobian) puts every judged parameter (:data:`PARAMS`) within
    ``options.warm_rel`` of its scale (as :func:`judge_spread` measures spreads; a fifth of the level it calls
    not determined): its poses fix them, so a refinement from a nearby start converges to the minimum a
    calibration from scratch finds, and a warm-started refit with such ``±`` stands in for one from scratch."""
    for k in PARAMS:
        js = _fit_std(calib, k)
        scale = _scale(calib, k)
        if js is None or not (np.isfinite(js) and scale > 0) or js > options.warm_rel * scale:
            return False
    return True
