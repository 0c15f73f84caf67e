"""The phase decoder on synthetic captures whose truth is exact: a camera that sees the projector's panel pixel for
pixel (camera pixel (x, y) sees projector pixel (x, y)), with a known response, blur and noise."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from procam import decode, patterns
from procam.decode.decoded import LOW_MODULATION, OK, ORDER_DISAGREE, SATURATED, SHADOW
from procam.errors import ProcamWarning
from procam.decode.phase import PhaseOptions, decode_phase, response, unwrap
from procam.decode.phase.wrapped import Scratch, SumPlan, block_sums
from conftest import expect_warning

W, H = 256, 160


def panel(ps, *, noise=0.0, blur=0.0, gamma=1.0, alpha=20.0, beta=200.0, seed=0, dtype=np.uint8, clip=True):
    """(K, H, W) capture of ``ps`` by a camera that sees the panel 1:1: ``alpha + beta * (v/255)^gamma`` plus
    Gaussian noise (DN), the light blurred along each pattern's axis by ``blur`` projector pixels."""
    rng = np.random.default_rng(seed)
    out = np.empty((ps.count, ps.height, ps.width), dtype)
    top = np.iinfo(dtype).max
    for k in range(ps.count):
        axis, line = ps.line(k)
        if axis is None:
            light = np.full((ps.height, ps.width), 1.0 if k == ps.white else 0.0)
        else:
            lit = (line.astype(np.float64) / 255.0) ** gamma
            if blur > 0:
                lit = gaussian_filter1d(lit, blur, mode="nearest")
            light = np.broadcast_to(lit[None, :] if axis == "col" else lit[:, None], (ps.height, ps.width))
        img = alpha + beta * light + noise * rng.standard_normal((ps.height, ps.width))
        out[k] = np.clip(np.rint(img), 0, top) if clip else np.rint(img)
    return out


def truth():
    return np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))


@pytest.mark.parametrize("steps", [3, 4, 5, 7, 8, 9])
@pytest.mark.parametrize("start, shift, sign", [(0.0, 1, 1), (1.3, -1, 1), (-np.pi / 2, 1, -1)])
def test_nstep_phase_of_any_steps_and_conventions_is_exact(steps, start, shift, sign):
    block = patterns.Block("phase", "col", 0, steps, 20.0, fringe=patterns.Fringe(sign=sign, shift=shift, start=start))
    phi = np.linspace(0, 2 * np.pi, 50, endpoint=False)
    values = 120 + 90 * np.cos(phi[None, :] + block.shifts()[:, None])
    A, B, psi = response.nstep(values, block.shifts())
    assert np.allclose(A, 120) and np.allclose(B, 90)
    assert np.allclose(np.angle(np.exp(1j * (psi - phi))), 0, atol=1e-12)
    # the decoder's integer-grouped sums (in reused buffers, 8- and 16-bit frames) are the same sums
    c, s = np.cos(block.shifts()), np.sin(block.shifts())
    pixels = np.rint(values[:, 7:13])  # (steps, 6): six pixels of different phases
    for dtype, scale in ((np.uint8, 1), (np.uint16, 257)):
        frames = [(p * scale).astype(dtype).reshape(2, 3) for p in pixels]
        plan = SumPlan(block.shifts())
        assert (plan.pairs is not None) == (steps % 2 == 0)  # even steps: sums over the half-turn pairs
        got = block_sums(frames, plan, Scratch(4, 3, steps, dtype), mean=True)
        for g, w in zip(got, (c, -s, np.full(steps, 1.0 / steps))):
            assert g.shape == (2, 3)
            assert np.allclose(g.ravel(), scale * (w @ pixels), rtol=1e-6, atol=1e-3)


def test_cv2_phase_is_within_2e_4_rad_of_atan2():
    import cv2

    rng = np.random.default_rng(1)
    c, s = rng.standard_normal((2, 200000)).astype(np.float32)
    err = np.angle(np.exp(1j * (cv2.phase(c, s).astype(np.float64) - np.arctan2(s, c))))
    assert np.abs(err).max() < 2e-4


@pytest.mark.parametrize("family, kw", [("phase", dict(steps=4, period=16)), ("heterodyne", dict(steps=3)),
                                        ("gray-phase", dict(steps=4, period=16)),
                                        ("gray-phase", dict(steps=3, period=16, inverse=False, complementary=False,
                                                            white_black=False))])
def test_noise_free_panel_decodes_to_every_pixel_centre(family, kw):
    """Pixel i of the projector is centred at coordinate i: the decode of its own (8-bit) patterns gives i back
    (to the patterns' rounding to whole grey levels)."""
    ps = patterns.pattern_set(W, H, family=family, **kw)
    res = decode_phase(panel(ps), ps, PhaseOptions(gamma=1.0))
    x, y = truth()
    assert res.valid.all()
    assert np.abs(res.col - x).max() < 0.05 and np.abs(res.row - y).max() < 0.05
    assert isinstance(res, decode.DecodeResult) and res.subpixel


def test_procam_patterns_put_phase_zero_on_the_left_edge_of_pixel_0():
    ps = patterns.pattern_set(64, 32, family="gray-phase", period=8)
    blk = ps.phase_blocks("col")[0]
    _, line = ps.line(blk.first)  # frame 0: cos(2 pi (i + 0.5) / 8)
    assert list(line[:8]) == [round(127.5 * (1 + np.cos(2 * np.pi * (i + 0.5) / 8))) for i in range(8)]
    _, bit = ps.line(ps.gray_block("col").first + 2 * (ps.gray_block("col").bits - 1))  # the finest ordinary bit
    assert list(bit[:24] > 0) == [False] * 8 + [True] * 16  # gray(0) = 0, gray(1) = 1, gray(2) = 3: bit 0


@pytest.mark.parametrize("steps", [3, 4, 8])
def test_predicted_sigma_matches_monte_carlo_spread(steps):
    """sigma_x = sigma_I sqrt(2/N) / B * P / (2 pi): the decoded coordinates' spread over a panel of pixels at the
    same modulation is what the decoder predicts, with the noise given and with the noise it measures."""
    ps = patterns.pattern_set(W, H, family="gray-phase", steps=steps, period=32)
    stack = panel(ps, noise=2.0, beta=150.0, seed=steps)
    x, y = truth()
    for opts in (PhaseOptions(gamma=1.0, camera_noise=2.0), PhaseOptions(gamma=1.0)):
        res = decode_phase(stack, ps, opts)
        ok = res.valid
        assert ok.mean() > 0.99
        err = (res.col - x)[ok]
        pred = res.sigma_col[ok]
        formula = np.sqrt(4.0 + 1 / 12) * np.sqrt(2.0 / steps) / 75.0 * 32 / (2 * np.pi)
        assert np.median(pred) == pytest.approx(formula, rel=0.1)
        assert np.std(err / pred) == pytest.approx(1.0, abs=0.07)


@pytest.mark.parametrize("family, kw", [("phase", dict(steps=8, periods=(16, 64))),
                                        ("heterodyne", dict(steps=4, periods=(15, 12, 10))),
                                        ("gray-phase", dict(steps=4, period=16))])
def test_a_16_bit_capture_decodes_like_its_8_bit_reading(family, kw):
    """A 12-bit camera's frames in uint16 (levels x 16, its noise x 16): the same coordinates, reasons and gamma
    as the 8-bit capture of the same light, within the noise's share of the rounding."""
    ps = patterns.pattern_set(W, H, family=family, **kw)
    light = dict(noise=1.0, gamma=2.2, beta=200.0, seed=11)
    s8 = panel(ps, **light)
    s16 = panel(ps, **{**light, "noise": 16.0, "alpha": 320.0, "beta": 3200.0}, dtype=np.uint16)
    r8, r16 = decode_phase(s8, ps, full_scale=255.0), decode_phase(s16, ps, full_scale=4095.0)
    x, y = truth()
    for r in (r8, r16):
        assert r.valid.mean() > 0.95
        assert np.sqrt(np.mean((r.col - x)[r.valid] ** 2)) < 0.1
        assert np.sqrt(np.mean((r.row - y)[r.valid] ** 2)) < 0.1
        assert r.phase.gamma == pytest.approx(2.2, abs=0.06)  # the fit's small bias on these panels: 0.01-0.035
    assert r16.phase.gamma == pytest.approx(r8.phase.gamma, abs=0.01)
    both = r8.valid & r16.valid
    assert both.sum() > 0.95 * both.size
    # the 12-bit frames quantise 16 times finer: their coordinates' noise is at most the 8-bit one's
    assert np.std((r16.col - x)[both]) <= 1.05 * np.std((r8.col - x)[both])


def test_gamma_is_measured_and_corrected():
    ps = patterns.pattern_set(W, H, family="gray-phase", steps=4, period=16)
    stack = panel(ps, noise=1.0, gamma=2.2, beta=220.0, seed=5)
    res = decode_phase(stack, ps)
    assert res.phase.gamma == pytest.approx(2.2, abs=0.08)
    x, _ = truth()
    ok = res.valid_col
    assert np.sqrt(np.mean((res.col - x)[ok] ** 2)) < 0.03
    assert not res.phase.warnings


def test_uncorrected_gamma_is_warned_about_and_errs_at_n_times_the_fringe_frequency():
    """With gamma 'none' the decoder says the projector is not linear, and the error it leaves oscillates N times
    per fringe period with the amplitude it states."""
    steps, period = 3, 32
    ps = patterns.pattern_set(W, H, family="gray-phase", steps=steps, period=period)
    stack = panel(ps, noise=0.5, gamma=2.2, beta=220.0, seed=6)
    with expect_warning(ProcamWarning, match="gamma"):
        res = decode_phase(stack, ps, PhaseOptions(gamma="none"))
    assert res.phase.gamma_used == 1.0 and res.phase.gamma == pytest.approx(2.2, abs=0.1)
    x, _ = truth()
    ok = res.valid_col
    err = (res.col - x)[ok]
    phase = 2 * np.pi * (x[ok] + 0.5) / period
    basis = np.column_stack([np.sin(steps * phase), np.cos(steps * phase), np.ones_like(phase)])
    coef, *_ = np.linalg.lstsq(basis, err, rcond=None)
    amplitude = np.hypot(coef[0], coef[1])
    assert amplitude > 0.5  # pixels, at 3 x the fringe frequency
    assert amplitude == pytest.approx(res.phase.gamma_error_px, rel=0.25)
    assert np.std(err - basis @ coef) < 0.3 * amplitude  # the harmonic is (nearly) all of it


def test_phase_lut_inverts_the_estimate_of_a_distorted_waveform():
    fringe = patterns.Fringe()
    shifts = patterns.Block("phase", "col", 0, 4, 20.0).shifts()
    c = response.waveform(fringe, 2.4, 20.0, 0.7)
    lut = response.phase_lut(c, shifts)
    phi = np.linspace(0, 2 * np.pi, 997, endpoint=False)
    _, _, psi = response.nstep(response.samples(c, phi, shifts), shifts)
    assert lut.max_error > 0.01
    got, _ = lut(psi)
    assert np.abs(np.angle(np.exp(1j * (got - phi)))).max() < 2e-4
    got32, _ = lut.apply(psi.astype(np.float32))
    assert np.abs(np.angle(np.exp(1j * (got32 - phi)))).max() < 5e-4


def test_shadow_and_saturation_are_marked():
    ps = patterns.pattern_set(W, H, family="gray-phase", steps=4, period=16)
    stack = panel(ps, noise=1.0, beta=200.0, seed=2)
    stack[:, :20, :30] = 25  # nothing projected reaches these pixels
    stack[:, 100:110, 100:120] = np.clip(stack[:, 100:110, 100:120].astype(int) + 120, 0, 255)  # over-exposed
    res = decode_phase(stack, ps, PhaseOptions(gamma=1.0))
    assert np.all(res.reason_col[:20, :30] == SHADOW) and np.all(res.reason_row[:20, :30] == SHADOW)
    assert np.all(res.reason_col[100:110, 100:120] == SATURATED)
    assert np.isnan(res.col[:20, :30]).all()


def test_orders_that_disagree_are_marked_never_guessed():
    """The cue's frames of one region come from a cue shifted by 3.4 fine periods: there the fine fringes and
    the cue disagree by 0.4 of a period; no such pixel is decoded, and every decoded one is right."""
    ps = patterns.pattern_set(W, H, family="phase", steps=4, period=16)
    stack = panel(ps, noise=0.5, seed=3)
    cue = ps.phase_blocks("col")[0]
    other = panel(patterns.PhaseSet(W, H, "phase", tuple(
        b if b.first != cue.first else patterns.Block("phase", "col", b.first, 4, b.period,
                                                      fringe=patterns.Fringe(origin=-0.5 + 3.4 * 16))
        for b in ps.blocks)), noise=0.5, seed=3)
    stack[cue.first:cue.first + 4, 40:80, :] = other[cue.first:cue.first + 4, 40:80, :]
    res = decode_phase(stack, ps, PhaseOptions(gamma=1.0))
    x, _ = truth()
    assert np.mean(res.reason_col[40:80] == ORDER_DISAGREE) > 0.6
    ok = res.valid_col
    assert np.abs(res.col - x)[ok].max() < 0.3


def test_too_noisy_a_cue_is_low_modulation():
    """Where the cue's noise could put the fine fringes in the wrong period (its predicted error above a tenth of
    a period) the pixel is marked, not decoded; the bright half decodes."""
    ps = patterns.pattern_set(W, H, family="phase", steps=4, period=8)
    stack = panel(ps, noise=1.0, beta=200.0, seed=4)
    stack[:, H // 2:] = panel(ps, noise=6.0, beta=40.0, seed=5)[:, H // 2:]
    res = decode_phase(stack, ps, PhaseOptions(gamma=1.0, camera_noise=None))
    x, _ = truth()
    assert np.mean(res.reason_col[H // 2:] == LOW_MODULATION) > 0.9
    assert res.valid_col[:H // 2].mean() > 0.95
    assert np.abs(res.col - x)[res.valid_col].max() < 0.5


def test_complementary_gray_removes_the_stripe_edge_errors_of_the_plain_hybrid():
    """Sharp stripes and noisy fringes (0.3 px blur, 3 DN noise on a 30 DN swing): near a period's edge the
    fringes' noise carries the phase across the wrap while the sharp Gray edge stays, so that either period is
    possible. The plain hybrid marks those pixels (orders disagree) rather than guess; the complementary bit
    decodes them, every one in the right period."""
    x, _ = truth()
    wrong, decoded, marked = {}, {}, {}
    for comp in (False, True):
        ps = patterns.pattern_set(W, H, family="gray-phase", steps=3, period=16, complementary=comp)
        stack = panel(ps, noise=3.0, beta=30.0, blur=0.3, seed=7)
        res = decode_phase(stack, ps, PhaseOptions(gamma=1.0))
        ok = res.valid_col
        wrong[comp] = int(np.sum(np.abs(res.col - x)[ok] > 8))
        decoded[comp] = ok.mean()
        marked[comp] = np.mean(res.reason_col == ORDER_DISAGREE)
    assert decoded[True] > 0.99 and wrong[True] == 0
    assert marked[False] > 0.05 and wrong[False] < 0.002 * ok.size


def test_heterodyne_beats_give_the_coordinate_and_mark_a_fringe_that_disagrees():
    l12, l23, l123 = patterns.phase.heterodyne_beats((1920 / 70, 1920 / 64, 1920 / 59))
    assert l12 == pytest.approx(1920 / 6) and l23 == pytest.approx(1920 / 5) and l123 == pytest.approx(1920)
    x_true, x0 = np.array([3.0, 123.4, 301.7, 620.2]), -0.5
    periods = (10.0, 11.0, 12.0)  # beats 110, 132 -> 660
    levels = [(((x_true - x0) / p) % 1.0, np.full(4, 1e-4), p, x0) for p in periods]
    reason = np.zeros(4, np.uint8)
    x, sx = unwrap.heterodyne(levels, reason)
    assert (reason == OK).all() and np.allclose(x, x_true, atol=1e-6)
    assert np.allclose(sx, 1e-4 / np.sqrt(sum(1 / p ** 2 for p in periods)))
    u3 = (levels[2][0] + 0.4) % 1.0  # the third fringe 0.4 of a period off
    reason = np.zeros(4, np.uint8)
    unwrap.heterodyne(levels[:2] + [(u3, np.full(4, 1e-4), 12.0, x0)], reason)
    assert (reason == ORDER_DISAGREE).all()


def test_gray_family_decode_is_unchanged_by_the_dispatch():
    ps = patterns.pattern_set(64, 48)
    st = patterns.generate(64, 48)
    a = decode.decode(st, ps)
    b = decode.decode_with(st, ps, decode.DecodeOptions())
    assert np.array_equal(a.col, b.col, equal_nan=True) and a.sigma_col is None and not a.subpixel
    assert np.allclose(a.coordinate_sigma("col")[a.valid_col], 1 / np.sqrt(12))


def test_the_response_fits_brent_search_is_scipys_bounded_search_bit_for_bit():
    """The gamma search runs Brent's bounded method itself (importing scipy.optimize cost a phase decode more than
    its own fit, issue 35): the same minimum, to the bit, as scipy's minimize_scalar(method="bounded")."""
    from scipy.optimize import minimize_scalar

    rng = np.random.default_rng(35)
    for k in range(600):
        c, lo, hi, tol = rng.uniform(-3, 5), *sorted(rng.uniform(-4, 6, 2)), 10 ** rng.uniform(-8, -1)
        f = [lambda x: (x - c) ** 2, lambda x: abs(x - c) ** 1.5 + 0.1 * np.sin(7 * x), lambda x: np.cos(x * c),
             lambda x: round((x - c) ** 2, 2)][k % 4]  # smooth, bumpy, several minima, flat steps
        want = float(minimize_scalar(f, bounds=(lo, hi), method="bounded", options={"xatol": tol}).x)
        assert response._brent(f, lo, hi, tol) == want


def test_a_phase_decode_imports_no_scipy(tmp_path):
    """Nothing paid at start-up that a phase decode does not need (issue 35): the response fit, the decode and
    the capture checks run without scipy."""
    import subprocess
    import sys
    from pathlib import Path

    ps = patterns.pattern_set(W, H, family="phase", steps=3, period=32, white_black=False)
    stack = panel(ps, noise=1.0, gamma=2.2, beta=220.0, seed=5)  # made here: this module imports scipy.ndimage
    path = Path(tmp_path) / "stack.npy"
    np.save(path, stack)
    code = ("import sys\nimport numpy as np\nfrom procam import patterns, decode\n"
            f"ps = patterns.pattern_set({W}, {H}, family='phase', steps=3, period=32, white_black=False)\n"
            f"res = decode.decode_with(np.load({str(path)!r}), ps)\n"
            "assert abs(res.phase.gamma - 2.2) < 0.1, res.phase.gamma\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'scipy'))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
