import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from procam import patterns

GOLDEN = Path(__file__).parent / "data" / "opencv_graycode_golden.json"


@pytest.mark.parametrize("w,h,count", [(1920, 1080, 46), (1024, 768, 42), (1280, 720, 44), (1280, 800, 44),
                                       (800, 600, 42), (37, 19, 24), (2, 2, 6)])
def test_counts(w, h, count):
    for order in patterns.ORDERS:
        ps = patterns.pattern_set(w, h, order)
        assert ps.count == count
        assert patterns.generate(w, h, order).shape == (count, h, w)


def test_gray_code_roundtrip_and_adjacency():
    x = np.arange(1 << 16)
    g = patterns.gray_encode(x)
    assert np.array_equal(patterns.gray_decode(g), x)
    # neighbouring codes differ in exactly one bit
    diff = g[1:] ^ g[:-1]
    assert np.all(diff & (diff - 1) == 0) and np.all(diff > 0)


@pytest.mark.parametrize("order", patterns.ORDERS)
@pytest.mark.parametrize("w,h", [(37, 19), (1280, 720)])
def test_inverses_flip_every_bit(order, w, h):
    ps = patterns.pattern_set(w, h, order)
    st = patterns.generate(w, h, order)
    for axis in ("col", "row"):
        for a, b in ps.pair_indices(axis):
            assert np.all(st[a].astype(int) + st[b] == 255)
    assert np.all(st[ps.white] == 255) and np.all(st[ps.black] == 0)


def test_moreno_order_is_centred_and_white_first():
    ps = patterns.pattern_set(1920, 1080, "moreno")
    assert (ps.white, ps.black, ps.col_offset, ps.row_offset) == (0, 1, 64, 484)
    st = patterns.generate(1920, 1080, "moreno")
    # METHOD §2: image 2 is the column MSB of gray(x + 64)
    expect = (patterns.gray_encode(np.arange(1920) + 64) >> 10) & 1
    assert np.array_equal(st[2, 0] > 0, expect.astype(bool))


def test_equal_to_opencv_graycodepattern_golden():
    """Golden file made with OpenCV 5.0.0's structured_light.GrayCodePattern (tools/make_opencv_graycode_golden.py)."""
    golden = json.loads(GOLDEN.read_text())
    assert golden["provenance"]["api"].startswith("cv2.structured_light.GrayCodePattern")
    for entry in golden["sizes"]:
        w, h = entry["width"], entry["height"]
        st = patterns.generate(w, h, "opencv")
        ps = patterns.pattern_set(w, h, "opencv")
        pats = np.ascontiguousarray(st[: ps.white])  # OpenCV's generate() has no white/black frames
        assert len(pats) == entry["count"]
        assert sorted(np.unique(pats).tolist()) == entry["values"]
        assert hashlib.sha256(pats.tobytes()).hexdigest() == entry["sha256"], (w, h)
        for k, p in enumerate(pats):
            assert np.packbits(p[0] > 0).tobytes().hex() == entry["row0_packbits"][k]
            assert np.packbits(p[:, 0] > 0).tobytes().hex() == entry["col0_packbits"][k]


def test_equal_to_opencv_contrib_when_installed():
    cv2 = pytest.importorskip("cv2")
    if not hasattr(cv2, "structured_light"):
        pytest.skip("opencv-contrib not installed (optional)")
    for w, h in [(37, 19), (640, 480)]:
        _, pats = cv2.structured_light.GrayCodePattern.create(w, h).generate()
        assert np.array_equal(np.array(pats), patterns.generate(w, h)[:-2])


def test_bad_sizes():
    with pytest.raises(ValueError):
        patterns.pattern_set(1, 10)
    with pytest.raises(ValueError):
        patterns.pattern_set(10, 10, "bogus")
