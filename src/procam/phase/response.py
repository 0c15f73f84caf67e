"""The projector's response in the fringes: what a non-linear projector (gamma) does to the N-step phase, how to
undo it, and how to measure it (and the camera's noise) from the frames themselves.

Model
    A pattern value ``v`` (a fraction of 255) becomes light ``v ** gamma``; the camera records, at each pixel,
    ``alpha + beta * g`` with ``alpha`` the ambient light and the projector's black level and ``beta`` the pixel's
    gain (albedo, vignetting, exposure).  A fringe ``v(t)`` (:meth:`procam.patterns.phase.Fringe.shape`) is then the
    periodic waveform ``g(t) = v(t) ** gamma = sum_h c_h cos(h t)``, whose harmonics the optics blur: harmonic ``h``
    of a period-``P`` fringe is attenuated by ``exp(-2 pi^2 s^2 h^2 / P^2)``, ``s`` the combined projector and
    camera blur in projector pixels (:func:`waveform`).
Phase error and its correction
    The N-step estimate (:mod:`procam.phase.wrapped`) of such a waveform is the true phase plus an error of period
    ``2 pi / N`` in the phase (a harmonic ``h`` leaks into it when ``h = m N +- 1``): N times the fringe frequency.
    It is a known function of the phase for a given waveform and shift set, so :func:`phase_lut` tabulates the
    inverse, estimate -> phase, and the decoder looks it up per pixel.  (Where the waveform is so distorted that the
    estimate is not monotonic in the phase -- 3 steps and gamma above about 2.4 -- it cannot be undone: pre-correct
    the patterns, or use more steps.)
Measurement (:func:`fit_response`)
    On a sample of well-lit pixels, for candidate ``(gamma, s)``: every phase block's phase from its lookup table,
    then ``alpha`` and ``beta`` per pixel by linear least squares over every phase frame and the white and black
    frames (pattern values 1 and 0, blur-free); the cost is the trimmed mean of the residual sum of squares over
    ``beta^2``.  ``gamma`` is what makes the frames one projector's response to the described patterns: within a
    block the harmonics (N >= 4), across blocks the shared ``alpha`` and ``beta`` (the modulation's ripple at N
    times the fringe frequency for 3 steps), and the white and black frames (the fringes' mean level).  Its
    standard deviation is the spread over four disjoint quarters of the sample divided by 2.  A sequence that
    determines it in none of these ways (3 steps, one block per period, no white or black frame) leaves it
    unmeasured (``measurable = False``).
    The residuals at the optimum give the camera's noise: per pixel the residual variance (over ``frames - 2 -
    blocks`` degrees of freedom), as a function of the pixel's level, ``var = a + b * level`` (read and
    quantisation noise plus shot noise) fitted to binned medians.
Failure modes
    Pixels on the edges of the board's squares mix two albedos (their blocks disagree on ``beta``): the cost is
    trimmed and the noise fitted to medians.  Frames that are not what the description says make every ``gamma``
    fit badly (:mod:`procam.phase.diagnose` names them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

#: Harmonics of the fringe waveform kept in the model.
HARMONICS = 8
#: Entries of a phase lookup table over [0, 2 pi].
LUT_SIZE = 2048
#: Pixels of the sample the response is measured on.
FIT_PIXELS = 2000
#: Candidate gammas and blurs (projector pixels) of the coarse search.
GAMMA_GRID = np.round(np.arange(0.4, 3.61, 0.2), 2)
BLUR_GRID = (0.0, 1.0, 2.0)


@lru_cache(maxsize=64)
def harmonics(fringe, gamma: float, n: int = HARMONICS) -> np.ndarray:
    """(n + 1,) cosine-series coefficients ``c_0 .. c_n`` of the light ``v(t) ** gamma`` of ``fringe`` (its pattern
    values as fractions of 255, :meth:`~procam.patterns.phase.Fringe.shape`)."""
    t = np.linspace(0.0, 2.0 * np.pi, 512, endpoint=False)
    g = fringe.shape(t) ** float(gamma)
    c = np.fft.rfft(g).real / len(t)
    c[1:] *= 2.0
    return c[:n + 1]


def waveform(fringe, gamma: float, period: float, blur: float) -> np.ndarray:
    """The coefficients of :func:`harmonics` with harmonic ``h`` attenuated by the blur ``exp(-2 pi^2 blur^2 h^2 /
    period^2)`` (blur in projector pixels; the mean, ``c_0``, is unchanged)."""
    c = harmonics(fringe, round(float(gamma), 6)).copy()
    h = np.arange(len(c))
    c *= np.exp(-2.0 * np.pi ** 2 * float(blur) ** 2 * h ** 2 / float(period) ** 2)
    return c


def samples(c: np.ndarray, phase: np.ndarray, shifts: np.ndarray) -> np.ndarray:
    """(N, ...) the waveform ``c`` at ``phase + shift_k`` for every shift."""
    t = np.asarray(phase)[None] + np.asarray(shifts).reshape((-1,) + (1,) * np.ndim(phase))
    z = np.exp(1j * t)
    out = np.full(t.shape, c[0])
    zh = np.ones_like(z)
    for h in range(1, len(c)):
        zh = zh * z
        out = out + c[h] * zh.real
    return out


def nstep(values: np.ndarray, shifts: np.ndarray):
    """The N-step estimates of samples ``values`` (N, ...) taken at ``shifts`` (N,): ``(mean, modulation,
    phase)``, phase in [0, 2 pi); least squares for equally spaced shifts: ``phase = atan2(-sum I_k sin d_k,
    sum I_k cos d_k)``, ``modulation = 2 / N |sum I_k exp(-i d_k)|``."""
    v = np.asarray(values, np.float64)
    d = np.asarray(shifts, np.float64).reshape((-1,) + (1,) * (v.ndim - 1))
    C = np.sum(v * np.cos(d), axis=0)
    S = np.sum(v * np.sin(d), axis=0)
    n = v.shape[0]
    return v.mean(axis=0), 2.0 / n * np.hypot(C, S), np.mod(np.arctan2(-S, C), 2.0 * np.pi)


@dataclass(frozen=True)
class PhaseLUT:
    """The correction of one block's N-step phase: ``phase = estimate + correction(estimate)``.

    correction : (LUT_SIZE + 1,) radians on the estimate grid ``2 pi k / LUT_SIZE`` (periodic).
    slope : (LUT_SIZE + 1,) ``d phase / d estimate`` there (scales the noise).
    max_error : the largest ``|estimate - phase|`` uncorrected, radians.
    """

    correction: np.ndarray
    slope: np.ndarray
    max_error: float

    def __call__(self, psi: np.ndarray):
        """``(phase, slope)`` at estimates ``psi`` (radians in [0, 2 pi))."""
        q = np.asarray(psi) * (LUT_SIZE / (2.0 * np.pi))
        return (psi + np.interp(q, np.arange(LUT_SIZE + 1), self.correction),
                np.interp(q, np.arange(LUT_SIZE + 1), self.slope))


def phase_lut(c: np.ndarray, shifts: np.ndarray) -> PhaseLUT | None:
    """The :class:`PhaseLUT` of waveform ``c`` sampled at ``shifts``; None when the N-step estimate is not
    monotonic in the phase (the waveform cannot be corrected)."""
    m = 4 * LUT_SIZE
    phi = np.arange(m) * (2.0 * np.pi / m)
    vals = samples(c, phi, shifts)
    _, _, psi = nstep(vals, shifts)
    err = np.angle(np.exp(1j * (psi - phi)))
    est = phi + err
    if not np.all(np.diff(est) > 0):
        return None
    grid = np.arange(LUT_SIZE + 1) * (2.0 * np.pi / LUT_SIZE)
    # extend one period either side so the interpolation covers [0, 2 pi] whatever the offset
    ext_est = np.concatenate([est - 2 * np.pi, est, est + 2 * np.pi])
    ext_phi = np.concatenate([phi - 2 * np.pi, phi, phi + 2 * np.pi])
    true = np.interp(grid, ext_est, ext_phi)
    slope = np.gradient(true, grid)
    return PhaseLUT(true - grid, slope, float(np.max(np.abs(err))))


@dataclass(frozen=True)
class Response:
    """What :func:`fit_response` found.

    gamma : the projector's gamma (NaN when not measurable); gamma_std its standard deviation.
    blur : the effective blur of the fringes' harmonics, projector pixels.
    noise : ``(a, b)``: the camera's noise variance ``a + b * level`` (DN^2 at the input scale).
    pixels : pixels the fit used.
    measurable : whether the sequence determines gamma (else ``gamma`` is NaN and ``note`` says why).
    note : one line, '' when all went well.
    """

    gamma: float
    gamma_std: float
    blur: float
    noise: tuple
    pixels: int
    measurable: bool
    note: str = ""


def _fit_cost(data, gamma: float, blur: float, per_pixel: bool = False):
    """The cost of ``(gamma, blur)`` on ``data`` (see :func:`fit_response`); with ``per_pixel``, the residual sums
    of squares, the fitted beta and the pixels' levels as well."""
    Y = data["Y"]
    G = np.empty_like(Y)
    row = 0
    for blk, psi in data["blocks"]:
        c = waveform(blk.fringe, gamma, blk.period, blur)
        lut = phase_lut(c, blk.shifts())
        if lut is None:
            return (np.inf, None, None, None) if per_pixel else np.inf
        phi, _ = lut(psi)
        G[row:row + blk.steps] = samples(c, phi, blk.shifts())
        row += blk.steps
    G[row:] = data["fixed"]
    Gm, Ym = G.mean(0), Y.mean(0)
    dG, dY = G - Gm, Y - Ym
    sgg = np.einsum("sn,sn->n", dG, dG)
    beta = np.einsum("sn,sn->n", dG, dY) / np.maximum(sgg, 1e-12)
    rss = np.maximum(np.einsum("sn,sn->n", dY, dY) - beta ** 2 * sgg, 0.0)
    r = rss / np.maximum(beta ** 2, 1e-12)
    keep = np.sort(r)[: max(1, int(0.9 * len(r)))]
    cost = float(np.mean(keep))
    return (cost, rss, beta, Ym) if per_pixel else cost


def _golden(f, lo: float, hi: float, iters: int = 14) -> float:
    g = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = lo, hi
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(iters):
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = f(d)
    return (a + b) / 2.0


def _noise(rss, beta, level, dof: int, floor: float):
    """``(a, b)`` of ``var = a + b * level`` from per-pixel residuals (binned medians, chi-square corrected)."""
    var = rss / dof
    med_factor = (1.0 - 2.0 / (9.0 * dof)) ** 3  # median of chi2_dof / dof (Wilson-Hilferty)
    edges = np.quantile(level, np.linspace(0, 1, 9))
    xs, ys = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (level >= lo) & (level <= hi)
        if m.sum() >= 20:
            xs.append(float(np.median(level[m])))
            ys.append(float(np.median(var[m])) / med_factor)
    xs, ys = np.array(xs), np.array(ys)
    if len(xs) < 2 or np.ptp(xs) < 1e-6 * max(1.0, float(np.max(np.abs(xs)))):
        return max(float(np.median(var)) / med_factor, floor), 0.0
    (a, b), *_ = np.linalg.lstsq(np.column_stack([np.ones_like(xs), xs]), ys, rcond=None)
    if b < 0:
        a, b = float(np.median(ys)), 0.0
    if a < floor:
        a = floor
    return float(a), float(b)


def fit_response(blocks, white=None, black=None, *, gamma: float | None = None, quantum: float = 1.0,
                 seed: int = 0) -> Response:
    """Measure the projector's gamma and the camera's noise on a sample of pixels (the module docstring).

    Parameters
    ----------
    blocks : list of ``(block, values)``: every phase block (:class:`procam.patterns.phase.Block`) with its
        samples (N, n) at the same n pixels.
    white, black : (n,) the white and black frames there, or None.
    gamma : fix gamma to this value (only the blur and the noise are fitted).
    quantum : one grey level at the input scale (the noise floor is its quantisation, ``quantum^2 / 12``).

    Returns
    -------
    :class:`Response`.
    """
    n = blocks[0][1].shape[1]
    take = np.arange(n)
    if n > FIT_PIXELS:
        take = np.sort(np.random.default_rng(seed).choice(n, FIT_PIXELS, replace=False))
    fixed = [np.ones(len(take)) for v in (white,) if v is not None] + [np.zeros(len(take)) for v in (black,)
                                                                          if v is not None]
    ys = [np.asarray(v, np.float64)[:, take] for _, v in blocks]
    ys += [np.asarray(v, np.float64)[take][None] for v in (white, black) if v is not None]

    def data_of(idx):
        return {"Y": np.concatenate(ys, axis=0)[:, idx],
                "blocks": [(b, nstep(np.asarray(v, np.float64)[:, take][:, idx], b.shifts())[2]) for b, v in blocks],
                "fixed": np.array(fixed)[:, idx] if fixed else np.zeros((0, len(idx)))}

    every = np.arange(len(take))
    data = data_of(every)
    dof = sum(b.steps for b, _ in blocks) + len(fixed) - 2 - len(blocks)
    floor = quantum ** 2 / 12.0
    gammas = GAMMA_GRID if gamma is None else np.array([float(gamma)])
    costs = np.array([[_fit_cost(data, g, s) for s in BLUR_GRID] for g in gammas])
    gi, si = np.unravel_index(np.argmin(costs), costs.shape)
    blur = BLUR_GRID[si]
    note, measurable, std = "", True, 0.0
    if gamma is None:
        g0 = float(gammas[gi])
        lo, hi = max(0.3, g0 - 0.2), g0 + 0.2
        blur = _golden(lambda s: _fit_cost(data, g0, s), 0.0, 3.0, 10)
        g_hat = _golden(lambda g: _fit_cost(data, g, blur), lo, hi)
        folds = [every[k::4] for k in range(4)]
        est = [_golden(lambda g, d=data_of(f): _fit_cost(d, g, blur), lo - 0.2, hi + 0.2, 10) for f in folds]
        std = float(np.std(est, ddof=1) / 2.0)
        flat = np.ptp(costs[:, si][np.isfinite(costs[:, si])]) if np.isfinite(costs[:, si]).any() else 0.0
        if dof <= 0 or not std < 0.25 or flat < 0.05 * max(costs[gi, si], 1e-12):
            measurable = False
            note = ("the sequence does not determine the projector's gamma (no harmonic within a block, no shared "
                    "level across blocks, no white and black frames)")
        gamma_out = g_hat if measurable else float("nan")
    else:
        blur = _golden(lambda s: _fit_cost(data, float(gamma), s), 0.0, 3.0, 10)
        gamma_out = float(gamma)
    g_use = gamma_out if np.isfinite(gamma_out) else 1.0
    _, rss, beta, level = _fit_cost(data, g_use, blur, per_pixel=True)
    if rss is None or dof <= 0:
        noise = (floor, 0.0)
    else:
        noise = _noise(rss, beta, level, dof, floor)
    return Response(float(gamma_out), std, float(blur), noise, len(take), measurable, note)
