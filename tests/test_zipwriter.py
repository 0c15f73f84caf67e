"""procam.io.zipwriter: the parallel-deflated ZIP archive is zipfile's archive, byte for byte with zlib's deflate,
and with ISA-L's the same archive around other deflate streams of the same members."""

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


def _headers(archive: bytes):
    """The archive's members as zipfile reads them, without what depends on the deflate stream."""
    with zipfile.ZipFile(io.BytesIO(archive)) as zf:
        return [(i.filename, i.date_time, i.compress_type, i.flag_bits, i.external_attr, i.create_system,
                 i.create_version, i.extract_version, i.CRC, i.file_size) for i in zf.infolist()]


@pytest.mark.parametrize("level", [0, 2, 3])
def test_isal_deflates_the_same_archive_with_its_own_streams(level):
    """ISA-L's streams inflate to the members, the headers are zipfile's but for the compressed sizes and offsets,
    the archive is the same for any number of threads, and compresses as well as zlib's level 1 at level 2."""
    pytest.importorskip("isal")
    members = _members()
    one, three = io.BytesIO(), io.BytesIO()
    assert zipwriter.write(one, members, level, threads=1, deflater="isal")
    assert zipwriter.write(three, members, level, threads=3, deflater="isal")
    assert one.getvalue() == three.getvalue()
    reference = _zipfiles(members, 1)
    assert _headers(one.getvalue()) == _headers(reference)
    with zipfile.ZipFile(io.BytesIO(one.getvalue())) as zf:
        assert zf.testzip() is None
        assert [(i.filename, zf.read(i)) for i in zf.infolist()] == [(n, bytes(d)) for n, d in members]
    if level == 2:
        assert len(one.getvalue()) <= 1.02 * len(reference)
        numpys = io.BytesIO()  # a NumPy integer is a level too
        assert zipwriter.write(numpys, members, np.int64(level), deflater="isal")
        assert numpys.getvalue() == one.getvalue()


@pytest.mark.parametrize("deflater, level", [("isal", 4), ("isal", -1), ("zlib", 10), ("gzip", 1), ("zlib", 1.0),
                                             ("zlib", True), ("zlib", "1")])
def test_a_deflater_or_level_it_does_not_have_is_refused_before_writing(deflater, level):
    buf = io.BytesIO()
    with pytest.raises(ValueError, match="no deflater"):
        zipwriter.write(buf, _members(), level, deflater=deflater)
    assert buf.getvalue() == b""


def test_write_npz_deflates_with_the_fast_deflater_and_numpy_loads_it(tmp_path):
    """write_npz's members are deflated by zipwriter.FAST (ISA-L where installed): NumPy loads the arrays exactly,
    and the same arrays give the same bytes."""
    rng = np.random.default_rng(2)
    arrays = {"col": rng.normal(size=(120, 160)).astype(np.float32), "valid": rng.random((120, 160)) > 0.5}
    a = files.write_npz(tmp_path / "a.npz", **arrays).read_bytes()
    assert files.write_npz(tmp_path / "b.npz", **arrays).read_bytes() == a
    deflater, level = zipwriter.FAST
    buf = io.BytesIO()
    members = []
    for name, v in arrays.items():
        m = io.BytesIO()
        np.lib.format.write_array(m, v, allow_pickle=False)
        members.append((f"{name}.npy", m.getbuffer()))
    assert zipwriter.write(buf, members, level, deflater=deflater) and buf.getvalue() == a
    with np.load(tmp_path / "a.npz") as z:
        assert all(np.array_equal(z[k], v) for k, v in arrays.items())
    try:
        import isal  # noqa: F401
    except ImportError:
        assert zipwriter.FAST == ("zlib", files.NPZ_LEVEL)
    else:
        assert zipwriter.FAST == ("isal", 2)


def test_an_archive_too_large_is_left_to_zipfile_and_write_npz_writes_the_same_file(tmp_path, monkeypatch):
    """Over the limit ``write`` writes nothing and says so; ``write_npz`` then writes with zipfile: the same bytes
    as the parallel path, and a file NumPy loads."""
    rng = np.random.default_rng(1)
    arrays = {"col": rng.normal(size=(120, 160)).astype(np.float32), "valid": rng.random((120, 160)) > 0.5}
    monkeypatch.setattr(zipwriter, "FAST", ("zlib", files.NPZ_LEVEL))  # zipfile's deflate: the same bytes
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
