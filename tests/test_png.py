"""procam.io.png: the PNGs it decodes come out as OpenCV decodes them, bit for bit; the rest is left to OpenCV."""

import io
import itertools
import zlib

import cv2
import numpy as np
import pytest

from procam.errors import CaptureError
from procam.io import images as _images
from procam.io import png

FAST = {"none": cv2.IMWRITE_PNG_FILTER_NONE, "sub": cv2.IMWRITE_PNG_FILTER_SUB, "up": cv2.IMWRITE_PNG_FILTER_UP}
SLOW = {"average": cv2.IMWRITE_PNG_FILTER_AVG, "paeth": cv2.IMWRITE_PNG_FILTER_PAETH}


def _image(shape, dtype, seed):
    """Noise over a smooth ramp (the filters see both), full range of ``dtype``."""
    rng = np.random.default_rng(seed)
    top = np.iinfo(dtype).max
    ramp = np.linspace(0, 1, shape[1])[None, :] * np.linspace(0.2, 1, shape[0])[:, None]
    if len(shape) == 3:
        ramp = ramp[:, :, None]
    img = (ramp + rng.normal(0, 0.15, shape)).clip(0, 1) * top
    return np.round(img).astype(dtype)


def _encode(img, filt):
    ok, buf = cv2.imencode(".png", img, [cv2.IMWRITE_PNG_FILTER, filt])
    assert ok
    return buf.tobytes()


def _decoded(data):
    parts, problem = png.chunks(data)
    assert problem is None
    return png.decode(data, parts)


def _opencv(data):
    return cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)


def _chunk(kind: bytes, body: bytes) -> bytes:
    """A PNG chunk ``kind`` holding ``body``, with its length and CRC."""
    return len(body).to_bytes(4, "big") + kind + body + (zlib.crc32(kind + body) & 0xFFFFFFFF).to_bytes(4, "big")


def _with_chunk(data, kind: bytes, body: bytes, after: bytes = b"IHDR"):
    """``data`` with a chunk ``kind`` (correct CRC) inserted after its first chunk ``after``."""
    parts, _ = png.chunks(data)
    end = next(e for k, s, e in parts if k == after) + 4
    return data[:end] + _chunk(kind, body) + data[end:]


SHAPES = [(1, 1), (1, 9), (7, 1), (13, 17), (48, 101)]


@pytest.mark.parametrize("filt", FAST)
def test_opencv_written_pngs_decode_here_to_opencvs_array(filt):
    """Every size, depth and channel count under None, Sub and Up: decoded here (not handed back), the same
    array as cv2.imdecode, and the image that was written."""
    for k, (shape, dtype, ch) in enumerate(itertools.product(SHAPES, (np.uint8, np.uint16), (1, 3))):
        img = _image(shape if ch == 1 else (*shape, ch), dtype, seed=k)
        data = _encode(img, FAST[filt])
        got = _decoded(data)
        assert got is not None, (shape, dtype, ch)
        ref = _opencv(data)
        assert got.dtype == ref.dtype and got.shape == ref.shape and got.flags.c_contiguous and got.flags.writeable
        assert np.array_equal(got, ref) and np.array_equal(got, img), (shape, dtype, ch)


@pytest.mark.parametrize("filt", FAST)
def test_an_8bit_grey_image_is_decoded_into_the_frame_given(filt, tmp_path):
    """``into`` (a frame of a stack) receives an 8-bit grey image of its size and is returned itself, also with
    the image's rows in several blocks; any other image (16-bit, colour, another size) leaves it untouched and
    comes back as a new array. read_images fills its stack the same way: the stack equals the images."""
    stack = np.full((3, 48, 101), 7, np.uint8)
    img = _image((48, 101), np.uint8, seed=11)
    data = _encode(img, FAST[filt])
    parts, _ = png.chunks(data)
    got = png.decode(data, parts, into=stack[1])
    assert got.base is stack and np.array_equal(stack[1], img) and np.array_equal(got, _opencv(data))
    assert (stack[0] == 7).all() and (stack[2] == 7).all()
    tall = _image((15000, 600), np.uint8, seed=12)
    frame = np.zeros_like(tall)
    d = _encode(tall, FAST[filt])
    assert png.decode(d, png.chunks(d)[0], into=frame) is frame
    assert np.array_equal(frame, tall)
    for other in (_image((48, 101), np.uint16, seed=13), _image((48, 101, 3), np.uint8, seed=14),
                  _image((47, 101), np.uint8, seed=15)):
        d = _encode(other, FAST[filt])
        out = png.decode(d, png.chunks(d)[0], into=stack[2])
        assert out.base is not stack and np.array_equal(out, _opencv(d)) and (stack[2] == 7).all()
    paths = []
    for k in range(3):
        paths.append(tmp_path / f"{k}.png")
        cv2.imwrite(str(paths[-1]), _image((48, 101), np.uint8, seed=20 + k), [cv2.IMWRITE_PNG_FILTER, FAST[filt]])
    ref = np.stack([cv2.imread(str(p), cv2.IMREAD_UNCHANGED) for p in paths])
    assert np.array_equal(_images.read_images(paths), ref)


@pytest.mark.parametrize("filt", SLOW)
def test_average_and_paeth_rows_and_alpha_are_left_to_opencv(filt, tmp_path):
    img = _image((20, 30), np.uint8, seed=1)
    data = _encode(img, SLOW[filt])
    assert _decoded(data) is None
    bgra = _image((20, 30, 4), np.uint8, seed=2)
    assert _decoded(_encode(bgra, FAST["sub"])) is None
    (tmp_path / "a.png").write_bytes(data)
    assert np.array_equal(_images.read_image(tmp_path / "a.png"), img)


def test_pillows_adaptive_filters_are_left_to_opencv(tmp_path):
    """Pillow picks a filter per row (Paeth among them): OpenCV decodes those, read_image gives its array."""
    from PIL import Image

    for k, img in enumerate((_image((40, 50), np.uint8, 3), _image((40, 50, 3), np.uint8, 4))):
        buf = io.BytesIO()
        Image.fromarray(img).save(buf, "PNG")
        data = buf.getvalue()
        assert _decoded(data) is None
        path = tmp_path / f"{k}.png"
        path.write_bytes(data)
        ref = _opencv(data)
        want = ref if ref.ndim == 2 else cv2.cvtColor(ref, cv2.COLOR_BGR2GRAY)
        assert np.array_equal(_images.read_image(path), want)


@pytest.mark.parametrize("kind", sorted(png.IGNORED))
def test_chunks_opencv_ignores_leave_the_pixels_as_opencv_reads_them(kind):
    img = _image((16, 24), np.uint8, seed=5)
    body = {b"gAMA": (45455).to_bytes(4, "big"), b"sRGB": b"\x00", b"pHYs": bytes(9), b"tIME": bytes(7),
            b"cHRM": bytes(32), b"sBIT": b"\x04", b"bKGD": b"\x00\x10"}.get(kind, b"key\x00value")
    if kind == b"iCCP":
        body = b"icc\x00\x00" + zlib.compress(b"not a profile")
    data = _with_chunk(_encode(img, FAST["sub"]), kind, body)
    got = _decoded(data)
    assert got is not None and np.array_equal(got, _opencv(data)) and np.array_equal(got, img)


def test_a_transparency_chunk_is_left_to_opencv():
    data = _with_chunk(_encode(_image((8, 8), np.uint8, 6), FAST["sub"]), b"tRNS", b"\x00\x05")
    assert _decoded(data) is None


def test_several_idat_chunks_and_a_tall_image_in_blocks():
    """Rows spread over many IDAT chunks; an image tall enough that the running sums are taken in blocks of rows
    (the column sums of Up carried from one block to the next)."""
    img = _image((64, 80), np.uint8, seed=7)
    data = _encode(img, FAST["sub"])
    parts, _ = png.chunks(data)
    stream = b"".join(data[s:e] for k, s, e in parts if k == b"IDAT")
    head = data[:parts[1][1] - 8] if parts[1][0] == b"IDAT" else None
    assert head is not None
    pieces = [stream[i:i + 97] for i in range(0, len(stream), 97)]
    split = head + b"".join(_chunk(b"IDAT", p) for p in pieces) + data[-12:]
    assert np.array_equal(_decoded(split), img)
    tall = _image((15000, 600), np.uint8, seed=8)
    assert 15000 > (2**31 - 1) // (255 * 600 + 255)  # more than one block
    for filt in ("sub", "up"):
        assert np.array_equal(_decoded(_encode(tall, FAST[filt])), tall)


def test_pythons_zlib_decodes_the_same(monkeypatch):
    img = _image((30, 40, 3), np.uint16, seed=9)
    data = _encode(img, FAST["sub"])
    fast = _decoded(data)
    monkeypatch.setattr(png, "_inflater", zlib)
    assert np.array_equal(_decoded(data), fast) and np.array_equal(fast, img)


@pytest.mark.parametrize("crc", ["isal-or-zlib", "zlib"])
def test_the_chunk_checksum_is_zlibs_taken_in_pieces(crc, monkeypatch):
    """The chunks' CRC-32 (ISA-L's where installed, else zlib's, in pieces small enough that neither lets the
    interpreter lock go) is zlib's ``crc32`` of the whole: chunks of every length around the pieces' size pass, and
    each fails with one bit of its contents flipped."""
    if crc == "zlib":
        monkeypatch.setattr(png, "_inflater", zlib)
    rng = np.random.default_rng(11)
    sizes = (0, 1, 4091, 4092, 4093, 8192 + 3, 70001)  # with the 4 bytes of its kind: around 4096 and 8192
    bodies = [rng.integers(0, 256, n, dtype=np.uint8).tobytes() for n in sizes]
    data = b"\x89PNG\r\n\x1a\n" + b"".join(_chunk(b"tEXt", b) for b in bodies) + _chunk(b"IEND", b"")
    parts, problem = png.chunks(data)
    assert problem is None and [data[s:e] for _, s, e in parts] == bodies + [b""]
    for (_, s, e), n in zip(parts, sizes):
        if n:
            bad = bytearray(data)
            bad[s + n // 2] ^= 0x10
            assert png.chunks(bytes(bad))[1] == "is damaged (tEXt chunk fails its checksum)", n
    assert png._CRC_PIECE <= 5 * 1024  # both let the lock go above 5 KB


def test_damaged_streams_and_odd_headers_are_said_in_one_line_or_left_to_opencv(tmp_path):
    """A stream with valid chunk checksums that does not inflate, or ends early, and a header of a zero size:
    damaged, said in one line naming the file (OpenCV refuses each too, after libpng printed its own lines); an
    interlaced or huge header, and a stream whose fault comes after its rows, are handed back to OpenCV."""
    data = _encode(_image((32, 32), np.uint8, seed=10), FAST["sub"])
    parts, _ = png.chunks(data)
    _, s, e = next(p for p in parts if p[0] == b"IDAT")

    def with_idat(body):
        return data[:s - 8] + _chunk(b"IDAT", body) + data[e + 4:]

    stream = data[s:e]
    cases = [(with_idat(stream[:10] + bytes(len(stream) - 10)), "its image data does not inflate"),
             (with_idat(zlib.compress(zlib.decompress(stream)[:-40])), "its image data ends early: 1016 of the 1056")]
    for w, h in ((0, 32), (32, 0), (1 << 31, 32)):
        ihdr = w.to_bytes(4, "big") + h.to_bytes(4, "big") + bytes([8, 0, 0, 0, 0])
        cases.append((data[:8] + _chunk(b"IHDR", ihdr) + data[33:], f"its header gives a size of {w} x {h} pixels"))
    for k, (bad, words) in enumerate(cases):
        assert png.chunks(bad)[1] is None and _opencv(bad) is None, words
        with pytest.raises(png.Damaged, match=words):
            _decoded(bad)
        (tmp_path / f"bad{k}.png").write_bytes(bad)
        with pytest.raises(CaptureError, match=f"bad{k}.png: is damaged \\({words}"):
            _images.read_image(tmp_path / f"bad{k}.png")

    def header(w, h, interlace=0):
        ihdr = w.to_bytes(4, "big") + h.to_bytes(4, "big") + bytes([8, 0, 0, 0, interlace])
        return data[:8] + _chunk(b"IHDR", ihdr) + data[33:]

    assert _decoded(header(32, 32)) is not None
    assert _decoded(header(32, 32, interlace=1)) is None
    assert _decoded(header(1 << 16, 1 << 16)) is None  # 4 GiB of rows: not allocated here
    # a stream that fails only after its rows (its checksum): libpng stops reading once it has the rows, and reads
    # such a file when the checksum is in an image data chunk of its own; OpenCV says what is wrong
    assert _decoded(with_idat(stream[:-4] + bytes(4))) is None


def test_read_image_gives_opencvs_grey_of_a_colour_png(tmp_path):
    for k, dtype in enumerate((np.uint8, np.uint16)):
        img = _image((21, 33, 3), dtype, seed=11 + k)
        path = tmp_path / f"c{k}.png"
        path.write_bytes(_encode(img, FAST["sub"]))
        assert np.array_equal(_images.read_image(path), cv2.cvtColor(_opencv(path.read_bytes()), cv2.COLOR_BGR2GRAY))
        assert np.array_equal(_images.read_image(path, gray=False), img)


def test_a_file_opencv_refuses_is_never_decoded_here():
    """Chunks out of place (text between the image data, a second header, image data dropped, repeated or empty)
    and random bytes changed with every checksum made right again: whatever decodes here, OpenCV decodes to the
    same array; what OpenCV refuses is handed back, or said to be damaged."""
    rng = np.random.default_rng(12)
    img = _image((40, 50), np.uint8, seed=12)
    small = [cv2.IMWRITE_PNG_FILTER, FAST["sub"], cv2.IMWRITE_PNG_ZLIBBUFFER_SIZE, 64]  # many small IDAT chunks
    data = cv2.imencode(".png", img, small)[1].tobytes()
    parts, _ = png.chunks(data)
    ch = [(k, data[s:e]) for k, s, e in parts]
    at = [i for i, (k, _) in enumerate(ch) if k == b"IDAT"]
    assert len(at) > 4
    text = (b"tEXt", b"key\x00value")
    variants = [ch[:at[2]] + [text] + ch[at[2]:], ch[:1] + ch, ch[:at[1]] + ch[at[1] + 1:],
                ch[:at[1]] + [ch[at[1]]] + ch[at[1]:], ch[:at[-1]] + ch[at[-1] + 1:],
                ch[:at[1]] + [(b"IDAT", b"")] + ch[at[1]:], ch[:-1] + [text] + ch[-1:]]
    files = [data[:8] + b"".join(_chunk(k, b) for k, b in v) for v in variants]
    for _ in range(3000):  # a few bytes changed anywhere, every checksum made right again
        b = bytearray(data)
        for _ in range(int(rng.integers(1, 4))):
            b[int(rng.integers(8, len(b)))] = int(rng.integers(0, 256))
        pos = 8
        while pos + 12 <= len(b) and (end := pos + 12 + int.from_bytes(b[pos:pos + 4], "big")) <= len(b):
            b[end - 4:end] = (zlib.crc32(bytes(b[pos + 4:end - 4])) & 0xFFFFFFFF).to_bytes(4, "big")
            pos = end
        files.append(bytes(b))
    fast = damaged = 0
    for f in files:
        parts, problem = png.chunks(f)
        try:
            got = png.decode(f, parts) if problem is None else None
        except png.Damaged:  # what is called damaged here, OpenCV refuses too
            assert _opencv(f) is None
            damaged += 1
            continue
        if got is not None:
            fast += 1
            ref = _opencv(f)
            assert ref is not None and ref.dtype == got.dtype and np.array_equal(ref, got)
    assert fast > 50 and damaged > 50  # the unchanged kinds of file did decode here, and broken streams were seen


def test_sizes_opencv_refuses_are_left_to_it(monkeypatch):
    """libpng refuses a side over 1 000 000 pixels; OpenCV's size limits set in its environment variables hold."""
    def one_row(w):
        raw = b"\x01" + bytes(w)
        head = w.to_bytes(4, "big") + (1).to_bytes(4, "big") + bytes([8, 0, 0, 0, 0])
        return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", head) + _chunk(b"IDAT", zlib.compress(raw))
                + _chunk(b"IEND", b""))

    assert _decoded(one_row(1_000_000)) is not None
    assert _decoded(one_row(1_000_001)) is None and _opencv(one_row(1_000_001)) is None
    data = _encode(_image((20, 30), np.uint8, seed=13), FAST["sub"])
    assert _decoded(data) is not None
    monkeypatch.setenv("OPENCV_IO_MAX_IMAGE_PIXELS", "100")
    assert _decoded(data) is None
