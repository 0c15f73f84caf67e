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
    The N-step estimate (:mod:`procam.decode.phase.wrapped`) of such a waveform is the true phase plus an error of period
    ``2 pi / N`` in the phase (a harmonic ``h`` leaks into it when ``h = m N +- 1``): N times the fringe frequency.
    It is a known function of the phase for a given waveform and shift set, so :func:`phase_lut` tabulates the
    inverse, estimate -> phase, and the decoder looks it up per pixel.  (Where the waveform is so distorted that the
    estimate is not monotonic in the phase -- 3 steps and gamma above about 2.4 -- it cannot be undone: pre-correct
    the patterns, or use more steps.)
Measurement (:func:`fit_response`)
    On a sample of well-lit pixels, for candidate ``(gamma, s)``: every phase block's phase from its lookup table
    (blocks of the same steps and conventions whose periods are within 10 % share one waveform),
    then ``alpha`` and ``beta`` per pixel by linear least squares over every phase frame and the white and black
    frames (pattern values 1 and 0, blur-free); the cost is the trimmed mean of the residual sum of squares over
    ``beta^2``.  ``gamma`` is what makes the frames one projector's response to the described patterns: within a
    block the harmonics (N >= 4), across blocks the shared ``alpha`` and ``beta`` (the modulation's ripple at N
    times the fringe frequency for 3 steps), and the white and black frames (the fringes' mean level).  A sequence that
    determines it in none of these ways (3 steps, one block per period, no white or black frame) leaves it
    unmeasured (``measurable = False``).  Its standard deviation is the sandwich estimate from the per-pixel
    costs' first and second derivatives (pixels taken as independent).
    The residuals at the optimum give the camera's noise: per pixel the residual variance, within the blocks of
    4 or more steps each fitted with its own level and gain (``N - 3`` degrees of freedom each: the blur of the
    fringes differs between the axes), else of the whole fit (``frames - 2 - blocks``), as a function of the
    pixel's level, ``var = a + b * level`` (read and quantisation noise plus shot noise) fitted to binned medians.
Failure modes
    Pixels on the edges of the board's squares mix two albedos (their blocks disagree on ``beta``): the cost is
    trimmed and the noise fitted to medians.  Frames that are not what the description says make every ``gamma``
    fit badly (:mod:`procam.decode.phase.diagnose` names them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

#: Harmonics of the fringe waveform kept in the model.
HARMONICS = 8
#: Entries of a phase lookup table over [0, 2 pi] (linear interpolation errs by under 1e-4 rad).
LUT_SIZE = 1024
#: Entries of the table :meth:`PhaseLUT.apply` looks the nearest up in (the decoder's lookup: an index, no
#: interpolation).
FINE_SIZE = 16384
#: Pixels of the sample the response is measured on.
FIT_PIXELS = 1200
#: Of them, the pixels the search for gamma and the blur evaluates its cost on (the noise uses all).
SEARCH_PIXELS = 600
#: Candidate gammas of the coarse search (at a blur of 1 projector pixel), refined by Brent's method.
GAMMA_GRID = (0.6, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5)


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
    """(N, ...) the waveform ``c`` at ``phase + shift_k`` for every shift: ``sum_h c_h (cos h phase cos h d_k -
    sin h phase sin h d_k)``, the harmonics of the phase by the angle-addition recurrence (once per pixel, not
    per shift: :func:`_harmonic_table`) and the sum over them one matrix product."""
    phase = np.asarray(phase, np.float64)
    out = _shift_weights(c, shifts) @ _harmonic_table(phase.reshape(-1), len(c))
    return out.reshape((len(shifts),) + phase.shape)


def _harmonic_table(x: np.ndarray, n: int) -> np.ndarray:
    """(2 n, P) ``cos (h x)`` over ``sin (h x)``, ``h = 0 .. n - 1``, of the phases ``x`` (P,) by the
    angle-addition recurrence."""
    X = np.empty((2 * n, x.size))
    ch, sh = X[:n], X[n:]
    ch[0], sh[0] = 1.0, 0.0
    if n > 1:
        ch[1], sh[1] = np.cos(x), np.sin(x)
    t = np.empty(x.size)
    for h in range(2, n):  # cos (h t) and sin (h t) from those of (h - 1) t and t
        np.multiply(ch[h - 1], ch[1], out=ch[h])
        ch[h] -= np.multiply(sh[h - 1], sh[1], out=t)
        np.multiply(sh[h - 1], ch[1], out=sh[h])
        sh[h] += np.multiply(ch[h - 1], sh[1], out=t)
    return X


def _shift_weights(c: np.ndarray, shifts: np.ndarray) -> np.ndarray:
    """(N, 2 n) the waveform ``c``'s weights of :func:`_harmonic_table` at the shifts: ``c_h cos h d_k`` and
    ``-c_h sin h d_k``."""
    hd = np.arange(len(c))[None] * np.asarray(shifts, np.float64)[:, None]
    cw = np.asarray(c, np.float64)[None]
    return np.concatenate([cw * np.cos(hd), -(cw * np.sin(hd))], axis=1)


def nstep(values: np.ndarray, shifts: np.ndarray):
    """The N-step estimates of samples ``values`` (N, ...) taken at ``shifts`` (N,): ``(mean, modulation,
    phase)``, phase in [0, 2 pi); least squares for equally spaced shifts: ``phase = atan2(-sum I_k sin d_k,
    sum I_k cos d_k)``, ``modulation = 2 / N |sum I_k exp(-i d_k)|``."""
    v = np.asarray(values, np.float64)
    d = np.asarray(shifts, np.float64)
    n = v.shape[0]
    A, C, S = (np.stack([np.full(n, 1.0 / n), np.cos(d), np.sin(d)]) @ v.reshape(n, -1)).reshape((3,) + v.shape[1:])
    return A, 2.0 / n * np.hypot(C, S), np.mod(np.arctan2(-S, C), 2.0 * np.pi)


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

    def apply(self, psi: np.ndarray, slope: bool = True):
        """``(phase, slope)`` float32 at float32 estimates ``psi`` (any shape; ``slope`` None unless asked), fast:
        the nearest entry of a table :data:`FINE_SIZE` entries fine, the linear interpolation of this one there
        (which differs from the linear interpolation at ``psi`` by at most ``|slope - 1| pi / FINE_SIZE``, that
        is ``2e-4 |slope - 1|`` rad)."""
        fine = getattr(self, "_fine", None)
        if fine is None:
            q = np.arange(FINE_SIZE + 1) * ((len(self.correction) - 1) / FINE_SIZE)
            grid = np.arange(len(self.correction))
            fine = (np.interp(q, grid, self.correction).astype(np.float32),
                    np.interp(q, grid, self.slope).astype(np.float32))
            object.__setattr__(self, "_fine", fine)
        psi = np.asarray(psi, np.float32)
        q = np.multiply(psi, np.float32(FINE_SIZE / (2.0 * np.pi)), dtype=np.float32)
        q += np.float32(0.5)
        idx = q.astype(np.intp)
        del q
        out = np.take(fine[0], idx, mode="clip")
        out += psi
        return out, (np.take(fine[1], idx, mode="clip") if slope else None)

    def __call__(self, psi: np.ndarray, slope: bool = True):
        """``(phase, slope)`` at estimates ``psi`` (radians in [0, 2 pi)); ``slope`` None unless asked."""
        size = len(self.correction) - 1
        q = np.asarray(psi) * (size / (2.0 * np.pi))
        grid = np.arange(size + 1)
        return psi + np.interp(q, grid, self.correction), (np.interp(q, grid, self.slope) if slope else None)


@lru_cache(maxsize=8)
def _basis(m: int, n: int):
    """``(phi, E)``: the ``m`` phases ``2 pi j / m`` and ``E[j, h - 1] = exp(i h phi_j)`` for ``h = 1 .. n``."""
    phi = np.arange(m) * (2.0 * np.pi / m)
    E = np.exp(1j * phi[:, None] * np.arange(1, n + 1)[None])
    phi.flags.writeable = E.flags.writeable = False
    return phi, E


@lru_cache(maxsize=64)
def _shift_sums(shifts: tuple, n: int):
    """``(a, b, a0)``: ``a_h = sum_k exp(i (h-1) d_k)``, ``b_h = sum_k exp(-i (h+1) d_k)`` (``h = 1 .. n``) and
    ``a0 = sum_k exp(-i d_k)`` of the shifts ``d_k``."""
    d = np.asarray(shifts, np.float64)
    h = np.arange(1, n + 1)[:, None]
    a = np.exp(1j * (h - 1) * d[None]).sum(axis=1)
    b = np.exp(-1j * (h + 1) * d[None]).sum(axis=1)
    return a, b, complex(np.exp(-1j * d).sum())


def phase_lut(c: np.ndarray, shifts: np.ndarray, size: int = LUT_SIZE) -> PhaseLUT | None:
    """The :class:`PhaseLUT` (``size`` entries) of waveform ``c`` sampled at ``shifts``; None when the N-step
    estimate is not monotonic in the phase (the waveform cannot be corrected)."""
    table = _correction(c, tuple(np.asarray(shifts, np.float64).tolist()), size)
    if table is None:
        return None
    correction, err = table
    grid = np.arange(size + 1) * (2.0 * np.pi / size)
    true = grid + correction
    slope = np.empty_like(true)
    slope[1:-1] = (true[2:] - true[:-2]) / (grid[2:] - grid[:-2])
    slope[0] = slope[-1] = 0.5 * (slope[1] + slope[-2])
    return PhaseLUT(correction, slope, float(np.max(np.abs(err))))


def _correction(c: np.ndarray, shifts: tuple, size: int):
    """``(correction, err)``: the phase minus the estimate on the estimate grid ``2 pi k / size`` (``size + 1``
    entries) and the estimate minus the phase on the phase grid (``2 size`` entries), of waveform ``c`` sampled at
    ``shifts``; None when the estimate is not monotonic in the phase."""
    m = 2 * size
    phi, E = _basis(m, len(c) - 1)
    # sum_k w(phi + d_k) exp(-i d_k), harmonic by harmonic: cos h(phi + d) exp(-i d) sums to
    # (exp(i h phi) sum_k exp(i (h-1) d_k) + exp(-i h phi) sum_k exp(-i (h+1) d_k)) / 2
    a, b, a0 = _shift_sums(shifts, len(c) - 1)
    c = np.asarray(c, np.float64)
    z = E @ (c[1:] * a) + np.conj(E @ np.conj(c[1:] * b)) + c[0] * a0
    z *= np.conj(E[:, 0])
    err = np.arctan2(z.imag, z.real)  # estimate - phase, wrapped
    est = phi + err
    if not np.all(est[1:] > est[:-1]):
        return None
    grid = np.arange(size + 1) * (2.0 * np.pi / size)
    # a few samples of the neighbouring periods either side, so the interpolation covers [0, 2 pi]
    k = 8
    ext_est = np.concatenate([est[-k:] - 2 * np.pi, est, est[:k] + 2 * np.pi])
    ext_phi = np.concatenate([phi[-k:] - 2 * np.pi, phi, phi[:k] + 2 * np.pi])
    return np.interp(grid, ext_est, ext_phi) - grid, err


#: Entries of the lookup tables the fit uses (coarser: the fit needs the phase to about 1e-3 rad).
FIT_LUT_SIZE = 256


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


def _groups(blocks) -> list:
    """Blocks that share one waveform in the fit: the same shifts and conventions and periods within 10 %
    (their harmonics blur alike); ``[(period, [indices]), ...]``."""
    out: list = []
    for i, b in enumerate(blocks):
        for g in out:
            ref = blocks[g[1][0]]
            if (ref.steps == b.steps and ref.fringe == b.fringe and np.allclose(ref.shifts(), b.shifts())
                    and abs(math.log(b.period / ref.period)) < 0.1):
                g[1].append(i)
                break
        else:
            out.append([b.period, [i]])
    for g in out:
        g[0] = float(np.exp(np.mean([math.log(blocks[i].period) for i in g[1]])))
    return out


def _with_places(data: dict) -> dict:
    """``data`` with what every evaluation of :func:`_fit_cost` reuses: per group the estimates' places on the
    tables' grid (``psi``) and the shared shifts (``shifts``)."""
    blocks = data["blocks"]
    return dict(data, psi=[_grid_place(np.concatenate([blocks[i][1] for i in m]), FIT_LUT_SIZE)
                           for _, m in data["groups"]],
                shifts=[tuple(blocks[m[0]][0].shifts().tolist()) for _, m in data["groups"]])


def _fit_cost(data, gamma: float, blur: float, per_pixel: bool = False):
    """The cost of ``(gamma, blur)`` on ``data`` (see :func:`fit_response`); with ``per_pixel``, the residual sums
    of squares, the fitted beta and the pixels' levels as well."""
    Y = data["Y"]
    G = np.empty_like(Y)
    blocks = [b for b, _ in data["blocks"]]
    waves, phis = [], []
    for g, (period, members) in enumerate(data["groups"]):
        ref = blocks[members[0]]
        c = waveform(ref.fringe, gamma, period, blur)
        table = _correction(c, data["shifts"][g], FIT_LUT_SIZE)
        if table is None:
            return (np.inf, None, None, None) if per_pixel else np.inf
        # the members share the shifts: one lookup and one evaluation for all of them
        psi, j, f = data["psi"][g]
        # the table's linear interpolation at the estimates (as np.interp computes it)
        corr = table[0]
        phi = corr[j + 1] - corr[j]
        phi *= f
        phi += corr[j]
        phi += psi
        waves.append(c)
        phis.append(phi)
    # the harmonics of every group's phases at once (one recurrence), each group its own weights
    X = _harmonic_table(np.concatenate(phis), len(waves[0])) if len({len(c) for c in waves}) == 1 else None
    at = 0
    for (period, members), c, phi, shifts in zip(data["groups"], waves, phis, data["shifts"]):
        ref = blocks[members[0]]
        if X is None:
            values = samples(c, phi, np.asarray(shifts))
        else:
            values = _shift_weights(c, np.asarray(shifts)) @ X[:, at:at + phi.size]
        at += phi.size
        values = values.reshape(ref.steps, len(members), -1)
        for j, i in enumerate(members):
            row = data["rows"][i]
            G[row:row + ref.steps] = values[:, j]
    G[data["nphase"]:] = data["fixed"]
    if "dY" not in data:  # the samples' own terms, the same at every evaluation
        Ym = Y.mean(0)
        dY = Y - Ym
        data.update(Ym=Ym, dY=dY, syy=np.einsum("sn,sn->n", dY, dY))
    Ym, dY = data["Ym"], data["dY"]
    dG = G - G.mean(0)
    sgg = np.einsum("sn,sn->n", dG, dG)
    beta = np.einsum("sn,sn->n", dG, dY) / np.maximum(sgg, 1e-12)
    rss = np.maximum(data["syy"] - beta ** 2 * sgg, 0.0)
    r = rss / np.maximum(beta ** 2, 1e-12)
    keep = np.sort(r)[: max(1, int(0.9 * len(r)))]
    cost = float(np.mean(keep))
    return (cost, rss, beta, Ym) if per_pixel else cost


def _grid_place(psi: np.ndarray, size: int):
    """``(psi, j, f)``: estimates ``psi`` (radians in [0, 2 pi)) at ``j + f`` on the grid of a
    :class:`PhaseLUT` of ``size`` entries (``j`` the entry below, ``f`` in [0, 1])."""
    q = np.asarray(psi, np.float64) * (size / (2.0 * np.pi))
    j = np.clip(np.floor(q), 0, size - 1).astype(np.intp)
    return psi, j, q - j


def _sandwich_std(data, gamma: float, blur: float, step: float = 0.02) -> float:
    """Standard deviation of the gamma minimising the summed per-pixel costs ``r_p``: ``sqrt(sum r_p'^2) /
    |sum r_p''|`` (the pixels independent), from ``r_p`` at ``gamma`` and ``gamma +- step``."""
    r = []
    for g in (gamma - step, gamma, gamma + step):
        _, rss, beta, _ = _fit_cost(data, g, blur, per_pixel=True)
        if rss is None:
            return float("inf")
        r.append(rss / np.maximum(beta ** 2, 1e-12))
    d1 = (r[2] - r[0]) / (2 * step)
    d2 = (r[2] - 2 * r[1] + r[0]) / step ** 2
    keep = r[1] <= np.quantile(r[1], 0.9)
    curv = abs(float(np.sum(d2[keep])))
    return float(np.sqrt(np.sum(d1[keep] ** 2)) / curv) if curv > 0 else float("inf")


def _brent(f, lo: float, hi: float, tol: float, max_evaluations: int = 500) -> float:
    """The minimum of ``f`` on ``[lo, hi]`` to ``tol`` (Brent's bounded method: golden sections with parabolic steps;
    about 7 evaluations per search here, against 8-14 for golden sections alone).

    Forsythe, Malcolm & Moler's ``fmin``, step for step as scipy's ``minimize_scalar(method="bounded")`` takes it
    (the same evaluations, the same minimum to the bit: tests/test_phase_response.py): written out here because
    importing ``scipy.optimize`` costs a phase decode more than its own fit (issue 35)."""
    sqrt_eps = math.sqrt(2.2e-16)
    golden_mean = 0.5 * (3.0 - math.sqrt(5.0))
    a, b = lo, hi
    # x the best point so far, w the second best, v the previous w (f of each in fx, fw, fv)
    x = w = v = a + golden_mean * (b - a)
    fx = fw = fv = f(x)
    d = e = 0.0  # the step taken and the one before it
    n = 1
    mid = 0.5 * (a + b)
    tol1 = sqrt_eps * abs(x) + tol / 3.0
    tol2 = 2.0 * tol1
    while abs(x - mid) > tol2 - 0.5 * (b - a):
        golden = True
        if abs(e) > tol1:  # a parabola through x, w, v
            golden = False
            r = (x - w) * (fx - fv)
            q = (x - v) * (fx - fw)
            p = (x - v) * q - (x - w) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            q = abs(q)
            r, e = e, d
            if abs(p) < abs(0.5 * q * r) and q * (a - x) < p < q * (b - x):  # its minimum inside, the step shrinking
                d = (p + 0.0) / q
                u = x + d
                if u - a < tol2 or b - u < tol2:
                    d = tol1 * _sign1(mid - x)
            else:
                golden = True
        if golden:
            e = (a - x) if x >= mid else (b - x)
            d = golden_mean * e
        u = x + _sign1(d) * max(abs(d), tol1)
        fu = f(u)
        n += 1
        if fu <= fx:
            if u >= x:
                a = x
            else:
                b = x
            v, fv = w, fw
            w, fw = x, fx
            x, fx = u, fu
        else:
            if u < x:
                a = u
            else:
                b = u
            if fu <= fw or w == x:
                v, fv = w, fw
                w, fw = u, fu
            elif fu <= fv or v == x or v == w:
                v, fv = u, fu
        mid = 0.5 * (a + b)
        tol1 = sqrt_eps * abs(x) + tol / 3.0
        tol2 = 2.0 * tol1
        if n >= max_evaluations:
            break
    return float(x)


def _sign1(t: float) -> float:
    """The sign of ``t``, 1 for zero."""
    return -1.0 if t < 0 else 1.0


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
    constant = max(float(np.median(var)) / med_factor, floor), 0.0
    # the slope (shot noise) only where the levels spread enough to tell it from the intercept
    if len(xs) < 2 or np.ptp(xs) < 0.3 * max(float(np.max(np.abs(xs))), 1e-9):
        return constant
    (a, b), *_ = np.linalg.lstsq(np.column_stack([np.ones_like(xs), xs]), ys, rcond=None)
    if a < floor:  # through the floor instead
        a = floor
        b = float(np.sum((ys - a) * xs) / np.sum(xs * xs))
    if b < 0:
        return constant
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
    rows = list(np.cumsum([0] + [b.steps for b, _ in blocks])[:-1])
    ys += [np.asarray(v, np.float64)[take][None] for v in (white, black) if v is not None]
    data = {"Y": np.concatenate(ys, axis=0), "rows": rows, "nphase": sum(b.steps for b, _ in blocks),
            "blocks": [(b, nstep(y, b.shifts())[2]) for (b, _), y in zip(blocks, ys)],
            "fixed": np.array(fixed) if fixed else np.zeros((0, len(take))),
            "groups": _groups([b for b, _ in blocks])}
    # the search for gamma and the blur on every other pixel (its cost is per evaluation, its precision ample);
    # the noise from all of them
    search = dict(data, Y=data["Y"][:, ::2], fixed=data["fixed"][:, ::2],
                  blocks=[(b, psi[::2]) for b, psi in data["blocks"]]) if len(take) >= 2 * SEARCH_PIXELS else data
    data, search = _with_places(data), _with_places(search)
    dof = sum(b.steps for b, _ in blocks) + len(fixed) - 2 - len(blocks)
    floor = quantum ** 2 / 12.0
    note, measurable, std = "", True, 0.0
    if gamma is None:
        costs = np.array([_fit_cost(search, g, 1.0) for g in GAMMA_GRID])
        gi = int(np.argmin(costs))
        g0 = float(GAMMA_GRID[gi])
        lo, hi = max(0.3, g0 - 0.3), g0 + 0.3
        # gamma and blur trade off against each other a little: refine them in turn
        blur = _brent(lambda s: _fit_cost(search, g0, s), 0.0, 3.0, 0.02)
        g_hat = _brent(lambda g: _fit_cost(search, g, blur), lo, hi, 0.002)
        blur = _brent(lambda s: _fit_cost(search, g_hat, s), 0.0, 3.0, 0.01)
        g_hat = _brent(lambda g: _fit_cost(search, g, blur), g_hat - 0.04, g_hat + 0.04, 0.001)
        std = _sandwich_std(search, g_hat, blur)
        finite = costs[np.isfinite(costs)]
        flat = float(np.ptp(finite)) if finite.size else 0.0
        if dof <= 0 or not std < 0.25 or flat < 0.05 * max(float(costs[gi]), 1e-12):
            measurable = False
            note = ("the sequence does not determine the projector's gamma (no harmonic within a block, no shared "
                    "level across blocks, no white and black frames)")
        gamma_out = g_hat if measurable else float("nan")
    else:
        blur = _brent(lambda s: _fit_cost(search, float(gamma), s), 0.0, 3.0, 0.01)
        gamma_out = float(gamma)
    g_use = gamma_out if np.isfinite(gamma_out) else 1.0
    _, rss, beta, level = _fit_cost(data, g_use, blur, per_pixel=True)
    within = _within_blocks(data, g_use, blur)
    if within is not None:  # blocks of 4 or more steps: each its own level and gain (blur differs by axis)
        noise = _noise(within[0], beta, level, within[1], floor)
    elif rss is None or dof <= 0:
        noise = (floor, 0.0)
    else:
        noise = _noise(rss, beta, level, dof, floor)
    return Response(float(gamma_out), std, float(blur), noise, len(take), measurable, note)


def _within_blocks(data, gamma: float, blur: float):
    """``(rss, dof)`` per pixel of the blocks of 4 or more steps, each fitted with its own ``alpha`` and ``beta``
    (``N - 3`` degrees of freedom each), or None without such blocks."""
    blocks = [b for b, _ in data["blocks"]]
    rss, dof = None, 0
    for period, members in data["groups"]:
        ref = blocks[members[0]]
        if ref.steps < 4:
            continue
        c = waveform(ref.fringe, gamma, period, blur)
        lut = phase_lut(c, ref.shifts(), FIT_LUT_SIZE)
        if lut is None:
            return None
        for i in members:
            blk, psi = data["blocks"][i]
            phi, _ = lut(psi, slope=False)
            G = samples(c, phi, blk.shifts())
            Y = data["Y"][data["rows"][i]:data["rows"][i] + blk.steps]
            dG, dY = G - G.mean(0), Y - Y.mean(0)
            sgg = np.einsum("sn,sn->n", dG, dG)
            b = np.einsum("sn,sn->n", dG, dY) / np.maximum(sgg, 1e-12)
            r = np.maximum(np.einsum("sn,sn->n", dY, dY) - b ** 2 * sgg, 0.0)
            rss = r if rss is None else rss + r
            dof += blk.steps - 3
    return None if rss is None else (rss, dof)
