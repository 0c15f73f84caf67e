"""The neighbours' ordering pass of a phase decode (procam.decode.phase.unwrap.neighbour_orders) was made cheaper
for issue 35; it must order the same pixels to the same values as the formulation before (kept here as the
reference: the sums per window made as b0fbb34 made them), on a rendered capture whose board's black squares it orders."""

import numpy as np
from sim_small import small_scene

from procam import patterns, simulate
from procam.decode.decoded import LOW_MODULATION, OK
from procam.decode.phase import decode_phase, unwrap


def reference(x, sx, reason, u, su, coarse, coarse_sd, period, x0, size, *, window, tolerance=unwrap.TOLERANCE,
              max_sigma=unwrap.MAX_SIGMA, passes=2):
    import cv2

    H, W = reason.shape
    # the sums run over 2 x 2 blocks of pixels (at their centres): a quarter of the work, and a plane whose moments
    # move by a fraction of a per cent
    f = 2
    Hb, Wb = H // f, W // f
    wb = max(3, (window // f) | 1)
    h = wb // 2
    Yb, Xb = (np.mgrid[0:Hb, 0:Wb].astype(np.float64) * f + (f - 1) / 2.0)

    def binned(a):
        return cv2.resize(np.ascontiguousarray(a[:Hb * f, :Wb * f], np.float64), (Wb, Hb),
                          interpolation=cv2.INTER_AREA) * float(f * f)

    def box(a):
        return cv2.boxFilter(a, cv2.CV_64F, (wb, wb), normalize=False, borderType=cv2.BORDER_CONSTANT)

    done = 0
    for _ in range(passes):
        cand = (reason == LOW_MODULATION) & np.isfinite(u) & (su <= max_sigma) & np.isfinite(coarse)
        cand[Hb * f:] = False
        cand[:, Wb * f:] = False
        if not cand.any():
            break
        ok = reason == OK
        n_b = binned(ok.astype(np.float64))
        iy, ix = np.nonzero(cand)
        by, bx_ = iy // f, ix // f
        # each quadrant of the window holds decoded pixels
        least = max(5.0, 0.05 * (h * f) ** 2)
        around = np.ones(len(iy), bool)
        for ay, ax in ((h, h), (h, 0), (0, h), (0, 0)):
            q = cv2.boxFilter(n_b, cv2.CV_64F, (h + 1, h + 1), anchor=(ax, ay), normalize=False,
                              borderType=cv2.BORDER_CONSTANT)
            around &= q[by, bx_] >= least
        iy, ix, by, bx_ = iy[around], ix[around], by[around], bx_[around]
        if not len(iy):
            break
        xv = np.where(ok, x - np.float32(x0), 0.0).astype(np.float64)
        x_b, xx_b = binned(xv), binned(xv * xv)
        S = {k: box(v)[by, bx_] for k, v in (("1", n_b), ("X", n_b * Xb), ("Y", n_b * Yb), ("XX", n_b * Xb * Xb),
                                             ("YY", n_b * Yb * Yb), ("XY", n_b * Xb * Yb), ("x", x_b),
                                             ("xX", x_b * Xb), ("xY", x_b * Yb), ("xx", xx_b))}
        # the plane and the rules of the order are shared (unwrap._ordered); what changed is how the sums are made
        take, xn = unwrap._ordered(S, iy, ix, u, coarse, coarse_sd, period, x0, size, tolerance, max_sigma)
        iy, ix = iy[take], ix[take]
        if not len(iy):
            break
        x[iy, ix] = xn[take]
        sx[iy, ix] = period * su[iy, ix]
        reason[iy, ix] = OK
        done += len(iy)
    return done


def test_neighbour_orders_as_before(monkeypatch):
    scene = small_scene().replace(read_noise=1.5)
    ps = patterns.pattern_set(*scene.proj_size, family="phase", steps=3, period=64, white_black=False)
    stack, _ = simulate.render(simulate.with_board_pose(scene, (15.0, 10.0, 0.0)), order=ps, seed=3)
    seen = []
    real = unwrap.neighbour_orders

    def both(*args, **kw):
        mine = [a.copy() if isinstance(a, np.ndarray) else a for a in args]
        want = reference(*mine, **kw)
        got = real(*args, **kw)
        seen.append(got)
        assert got == want
        for k in (0, 1, 2):  # x, sx, reason: updated in place
            np.testing.assert_array_equal(args[k], mine[k])
        return got

    monkeypatch.setattr(unwrap, "neighbour_orders", both)
    res = decode_phase(stack, ps)
    assert len(seen) == 2 and min(seen) > 100, seen  # both axes, each with pixels ordered by their neighbours
    assert (res.reason_col == OK).sum() > 0 and (res.reason_row == OK).sum() > 0


def test_a_phase_decode_in_two_threads_is_the_one_thread_decode():
    """Bands of camera rows and then the two axes' neighbour orders run side by side (issue 35: a phase capture's
    decode no slower than a Gray capture's); every map and histogram the same bits as one thread."""
    scene = small_scene().replace(read_noise=1.5)
    ps = patterns.pattern_set(*scene.proj_size, family="phase", steps=3, period=64, white_black=False)
    stack, _ = simulate.render(simulate.with_board_pose(scene, (15.0, 10.0, 0.0)), order=ps, seed=3)
    one, two = (decode_phase(stack, ps, band=16, threads=n) for n in (1, 2))
    arrays = [k for k, v in vars(one).items() if isinstance(v, np.ndarray)]
    assert {"col", "row", "sigma_col", "reason_row", "codes_col", "codes_row"} <= set(arrays)
    for k in arrays:
        np.testing.assert_array_equal(getattr(one, k), getattr(two, k), err_msg=k)
    assert (one.reason_col == OK).sum() > 1000
