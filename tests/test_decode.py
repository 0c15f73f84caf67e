import numpy as np
import pytest
from scipy.ndimage import uniform_filter1d

from procam import decode, patterns
from procam.io import files as _files

SIZES = [(1920, 1080), (1024, 768), (1280, 720), (800, 600), (37, 19)]


@pytest.mark.parametrize("order", patterns.ORDERS)
@pytest.mark.parametrize("w,h", SIZES)
def test_decode_of_patterns_is_exact(w, h, order):
    ps = patterns.pattern_set(w, h, order)
    st = patterns.generate(w, h, order)
    yy, xx = np.mgrid[:h, :w]
    for method in ("robust", "simple"):
        r = decode.decode(st, ps, method)
        assert r.valid.all()
        assert np.array_equal(r.col, xx) and np.array_equal(r.row, yy)
    # 16-bit input decodes identically
    r16 = decode.decode(st.astype(np.uint16) * 257, ps)
    assert np.array_equal(r16.col, xx) and np.array_equal(r16.row, yy)


def _capture(w, h, order, contrast=1.0, noise=0.0, ambient=20.0, black_level=0.02, seed=0, dtype=np.uint8):
    """The sequence seen pixel-for-pixel by a linear camera: ambient + contrast*255*(projector light) + noise."""
    rng = np.random.default_rng(seed)
    light = patterns.generate(w, h, order).astype(np.float32) / 255.0
    light = black_level + (1 - black_level) * light
    img = ambient + contrast * 200.0 * light + rng.normal(0.0, noise, light.shape)
    full = 255 if dtype == np.uint8 else 4095
    return np.clip(np.round(img * full / 255), 0, full).astype(dtype)


@pytest.mark.parametrize("order", patterns.ORDERS)
@pytest.mark.parametrize("method", ["robust", "simple"])
def test_noise_and_low_contrast(order, method):
    w, h = 1024, 768
    ps = patterns.pattern_set(w, h, order)
    st = _capture(w, h, order, contrast=0.2, noise=3.0, seed=1)
    r = decode.decode(st, ps, method)
    yy, xx = np.mgrid[:h, :w]
    exact = (r.col == xx) & (r.row == yy)
    assert exact.mean() >= 0.999
    # what is decoded is right: no wrong codes, only (rare) invalid pixels
    assert np.all((r.col == xx)[r.valid_col]) and np.all((r.row == yy)[r.valid_row])


def test_12bit_in_16bit_container():
    w, h = 320, 240
    ps = patterns.pattern_set(w, h)
    st = _capture(w, h, "opencv", contrast=0.2, noise=3.0, seed=2, dtype=np.uint16)  # noise 3 DN of 8 bits
    assert _files.full_scale_of(st) == 4095
    r = decode.decode(st, ps)
    yy, xx = np.mgrid[:h, :w]
    assert ((r.col == xx) & (r.row == yy)).mean() >= 0.999


def test_shadow_and_out_of_range_are_invalid_with_reasons():
    w, h = 48, 24
    ps = patterns.pattern_set(w, h, "moreno")  # centred codes: some codes fall outside the panel
    st = _capture(w, h, "moreno", noise=0.0)
    st[:, :8, :8] = 30  # a patch the projector does not reach: constant in every frame
    r = decode.decode(st, ps)
    assert not r.valid[:8, :8].any()
    assert np.all(r.reason_col[:8, :8] == decode.SHADOW)
    assert np.isnan(r.col[:8, :8]).all()
    assert r.valid[8:, 8:].all()
    # a code outside the projector: replace a column's patterns by those of code W + 1 (beyond the panel)
    big = patterns.bit_planes(2**ps.col_bits, ps.col_bits, 0)[:, w + ps.col_offset + 1]
    assert ps.col_offset > 0 and w + ps.col_offset + 1 < 2**ps.col_bits
    for (a, b), bit in zip(ps.pair_indices("col"), big):
        st[a, :, 20], st[b, :, 20] = (st[ps.white, :, 20], st[ps.black, :, 20]) if bit else \
            (st[ps.black, :, 20], st[ps.white, :, 20])
    r = decode.decode(st, ps)
    assert np.all(r.reason_col[8:, 20] == decode.OUT_OF_RANGE)


def _with_global_light(w, h, order, direct=50.0, global_=140.0, black_level=0.02, seed=3):
    """Interreflections (Nayar et al.): each pixel also receives up to `global_` times the mean projector
    light over a window of 60 % of the image around its mirror position (two facing surfaces), growing
    from nothing at the left edge to full strength at the right.  High-frequency patterns average to 1/2
    there; low-frequency ones do not, which fools the plain pattern-vs-inverse comparison wherever the
    global light outweighs the direct light."""
    rng = np.random.default_rng(seed)
    light = patterns.generate(w, h, order).astype(np.float32) / 255.0
    light = black_level + (1 - black_level) * light
    mirrored = light[:, ::-1, ::-1]
    glob = uniform_filter1d(uniform_filter1d(mirrored, 3 * w // 5, axis=2, mode="wrap"), 3 * h // 5, axis=1,
                            mode="wrap")
    ramp = np.linspace(0.0, 1.0, w, dtype=np.float32)[None, None, :]
    img = 10 + direct * light + global_ * ramp * glob + rng.normal(0, 1.0, light.shape)
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


def test_robust_classifier_under_global_illumination():
    w, h = 512, 256
    ps = patterns.pattern_set(w, h)
    st = _with_global_light(w, h, "opencv")
    yy, xx = np.mgrid[:h, :w]
    res = {m: decode.decode(st, ps, m) for m in ("simple", "robust")}
    wrong = {m: (np.count_nonzero(r.valid_col & (r.col != xx)) + np.count_nonzero(r.valid_row & (r.row != yy)))
             / (2 * w * h) for m, r in res.items()}
    # the simple comparison decodes many pixels to the wrong projector coordinate ...
    assert wrong["simple"] > 0.1
    # ... the robust classifier keeps half of them and (almost) nothing it keeps is wrong
    assert wrong["robust"] < 0.001
    assert res["robust"].valid.mean() > 0.4
    # Moreno's b = 0.5 doubles the direct-light estimate and makes the rule no better than the simple one
    r05 = decode.decode(st, ps, "robust", black_fraction=0.5)
    assert np.count_nonzero(r05.valid_col & (r05.col != xx)) / (w * h) > 0.1
    assert np.count_nonzero(res["robust"].reason_col == decode.AMBIGUOUS) > 0
    # where the simple rule is wrong, the robust one is right or says "uncertain"
    r = res["robust"]
    simple_wrong = res["simple"].valid_col & (res["simple"].col != xx)
    assert np.all((r.col == xx)[simple_wrong & r.valid_col])


def test_unresolved_fine_stripes_still_decode_coarsely():
    """A camera that cannot resolve the finest stripes (blur): the certain leading bits still give the
    projector coordinate to within the block they leave, instead of nothing."""
    import cv2

    w, h = 256, 128
    ps = patterns.pattern_set(w, h)
    st = _capture(w, h, "opencv", noise=1.0, seed=5)
    blurred = np.stack([cv2.GaussianBlur(im, (0, 0), 2.0) for im in st])
    strict = decode.decode(blurred, ps, max_dropped_bits=0)
    r = decode.decode(blurred, ps)
    assert strict.valid.mean() < 0.05
    assert r.valid.mean() > 0.5
    yy, xx = np.mgrid[:h, :w]
    assert r.dropped_col[r.valid_col].max() >= 1
    # the error stays within the block: at most 2^(dropped-1) + 1 px
    err = np.abs(r.col - xx)[r.valid_col]
    assert np.all(err <= 2.0 ** (r.dropped_col[r.valid_col].astype(float) - 1) + 1)
    assert np.abs(np.mean(r.col[r.valid_col] - xx[r.valid_col])) < 0.1  # unbiased


def test_bad_arguments():
    ps = patterns.pattern_set(37, 19)
    st = patterns.generate(37, 19)
    with pytest.raises(ValueError):
        decode.decode(st[:-1], ps)
    with pytest.raises(ValueError):
        decode.decode(st, ps, "magic")
    with pytest.raises(ValueError):
        decode.decode(st.astype(np.float32), ps)


@pytest.mark.parametrize("order", patterns.ORDERS)
def test_step_codes_blocks_and_decodes_to_their_centre(order):
    """kamino410-style graycode_step: one code per step x step block; decoded value = the block's centre."""
    w, h, step = 100, 60, 3
    ps = patterns.pattern_set(w, h, order, step)
    assert (ps.code_width, ps.code_height) == (34, 20)
    assert ps.count == 2 * (patterns.bits_for(34) + patterns.bits_for(20)) + 2
    st = patterns.generate(w, h, order, step=step)
    assert st.shape == (ps.count, h, w)
    # every block of step x step projector pixels is uniform in every pattern
    assert np.all(st[:, :, :99].reshape(ps.count, h, 33, 3) == st[:, :, :99:3][..., None])
    r = decode.decode(st, ps)
    yy, xx = np.mgrid[:h, :w]
    # the centre of each block; the last, partial block is clipped to the panel (column 99 is alone in it)
    lo_x, lo_y = (xx // step) * step, (yy // step) * step
    assert np.array_equal(r.col, (lo_x + np.minimum(lo_x + step - 1, w - 1)) / 2)
    assert np.array_equal(r.row, (lo_y + np.minimum(lo_y + step - 1, h - 1)) / 2)
    assert r.col[0, 99] == 99
    # the same sequence as OpenCV's GrayCodePattern of the reduced size, expanded (opencv order)
    if order == "opencv":
        small = patterns.generate(34, 20)
        assert np.array_equal(st, small[:, np.arange(h) // step][:, :, np.arange(w) // step])
