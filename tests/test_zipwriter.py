"""procam.io.zipwriter: the parallel-deflated ZIP archive is zipfile's archive, byte for byte."""

import io
import zipfile

import numpy as np
import pytest

from procam.io import files, zipwriter


def _members(seed=0):
    rng = np.random.default_rng(seed)
    noisy = rng.normal(size=(300, 400)).astype(np.float32)  # hardly compresses
    smooth = np.repeat(np.arange(300, dtype=np.float32), 400)  # compresses well
    return [("empty.npy", b""), ("tiny.npy", b"x"), ("noisy.npy", noisy.tobytes()),
            ("smooth.npy", memoryview(smooth)), ("maß.npy", rng.integers(0, 3, 10000, dtype=np.uint8).tobytes())]


def _zipfiles(members, level):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members:
            zf.writestr(zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0)), bytes(data),
                        compress_type=zipfile.ZIP_DEFLATED, compresslevel=level)
    return buf.getvalue()


@pytest.mark.parametrize("level", [1, 6])
@pytest.mark.parametrize("threads", [1, 3])
def test_the_archive_is_zipfiles_byte_for_byte(level, threads):
    members = _members()
    buf = io.BytesIO()
    assert zipwriter.write(buf, members, level, threads=threads)
    assert buf.getvalue() == _zipfiles(members, level)
    with zipfile.ZipFile(io.BytesIO(buf.getvalue())) as zf:
        assert zf.testzip() is None
        assert [(i.filename, zf.read(i)) for i in zf.infolist()] == [(n, bytes(d)) for n, d in members]


def test_an_archive_too_large_is_left_to_zipfile_and_write_npz_writes_the_same_file(tmp_path, monkeypatch):
    """Over the limit ``write`` writes nothing and says so; ``write_npz`` then writes with zipfile: the same bytes
    as the parallel path, and a file NumPy loads."""
    rng = np.random.default_rng(1)
    arrays = {"col": rng.normal(size=(120, 160)).astype(np.float32), "valid": rng.random((120, 160)) > 0.5}
    fast = files.write_npz(tmp_path / "fast.npz", **arrays).read_bytes()
    monkeypatch.setattr(zipwriter, "LIMIT", 1000)
    buf = io.BytesIO()
    assert zipwriter.write(buf, [("a", bytes(2000))], 1) is False and buf.getvalue() == b""
    monkeypatch.setattr(zipwriter, "LIMIT", (1 << 31) - 1)
    assert zipwriter.write(buf, [("a", b""), ("b", b"")], 1) and buf.getvalue()
    monkeypatch.setattr(zipwriter, "COUNT_LIMIT", 2)  # as many members as the end record can count: zipfile's
    buf = io.BytesIO()
    assert zipwriter.write(buf, [("a", b""), ("b", b"")], 1) is False and buf.getvalue() == b""
    slow = files.write_npz(tmp_path / "slow.npz", **arrays)
    assert slow.read_bytes() == fast
    with np.load(slow) as z:
        assert all(np.array_equal(z[k], v) for k, v in arrays.items())
