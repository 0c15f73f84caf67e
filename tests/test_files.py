"""File plumbing: atomic writes, full-scale detection, procam's marks (procam.io.files, procam.io.formats)."""

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import within

from procam import io
from procam.io import files as _files
from procam.io import formats
from procam.io import images as _images


def test_atomic_write_leaves_nothing_on_error(tmp_path):
    target = tmp_path / "out.json"
    with pytest.raises(RuntimeError):
        with _files.atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("boom")
    assert not target.exists() and not list(tmp_path.iterdir())


def test_full_scale_of_bit_depths():
    assert _files.full_scale_of(np.zeros((2, 2), np.uint8)) == 255
    assert _files.full_scale_of(np.full((2, 2), 1000, np.uint16)) == 1023
    assert _files.full_scale_of(np.full((2, 2), 4095, np.uint16)) == 4095
    assert _files.full_scale_of(np.full((2, 2), 4096, np.uint16)) == 16383
    assert _files.full_scale_of(np.full((2, 2), 65535, np.uint16)) == 65535


def test_every_file_procam_writes_carries_the_mark_procam_wrote_knows(tmp_path):
    """Each writer leaves the mark of io.formats, and files.procam_wrote knows it (no manifest here)."""
    from conftest import camera_view_of_patterns
    from sim_small import small_scene

    from procam import decode, export, patterns
    from procam.simulate import truth_calibration

    assert formats.NPZ_KEY not in formats.DECODED_MAPS_KEYS + formats.REMAP_MARK
    calib = truth_calibration(small_scene())
    ps = patterns.pattern_set(64, 32)
    written = [io.save_calibration(calib, tmp_path / "c.json"), io.save_calibration(calib, tmp_path / "c.yml"),
               io.save_calibration(calib, tmp_path / "c.xml"), io.save_kamino410(calib, tmp_path / "k.xml"),
               io.save_decoded_maps(tmp_path / "d.npz", decode.decode(camera_view_of_patterns(64, 32), ps)),
               io.save_maps(tmp_path / "m.npz", *export.undistort_maps(calib.camera)),
               io.write_image(tmp_path / "i.png", np.zeros((4, 4), np.uint8)),
               io.write_image(tmp_path / "i.jpg", np.zeros((4, 4, 3), np.uint8)),
               _files.write_text(tmp_path / "gl.json", json.dumps(export.opengl_document(calib, 10, 100)))]
    try:
        import plyfile  # noqa: F401

        written.append(io.write_ply(tmp_path / "p.ply", np.zeros((2, 3)), comments=[formats.PLY_COMMENT]))
    except ImportError:
        pass
    from matplotlib.figure import Figure

    from procam.plots import save_figure
    from procam.report.page import html_page, write_report

    written += [save_figure(Figure(figsize=(1, 1)), tmp_path / f"f.{ext}") for ext in ("png", "jpg", "jpeg", "pdf",
                                                                                         "svg")]
    written.append(write_report(html_page("t", "h", ["<p>x</p>"]), tmp_path / "r.html"))
    for path in written:
        assert _files.procam_wrote(path), path.name
    np.savez(tmp_path / "theirs.npz", col=np.zeros(2))
    (tmp_path / "theirs.yml").write_text("%YAML:1.0\nK: 1\n")
    # a page of the user's that only mentions the mark outside its head, and a photo (no comment)
    (tmp_path / "theirs.html").write_text('<html><head><title>x</title></head><body><meta name="generator" '
                                          'content="procam"></body></html>')
    import cv2

    cv2.imwrite(str(tmp_path / "theirs.jpg"), np.zeros((8, 8), np.uint8))
    for name in ("theirs.npz", "theirs.yml", "theirs.html", "theirs.jpg"):
        assert not _files.procam_wrote(tmp_path / name), name


def test_a_captures_frame_is_never_an_outputs_to_replace_once_out_of_its_folder(tmp_path):
    """A sequence's frames carry the frame's mark: in their folder its manifest lets their writer replace them
    (re-rendering); copied out of it (``cp pose/*.png``, the hidden manifest left behind) no output replaces one:
    a figure given that name was written over a frame of the capture."""
    import shutil

    from conftest import camera_view_of_patterns

    from procam import capture, patterns
    from procam.errors import OutputError

    ps = patterns.pattern_set(64, 32)
    frames = capture.write_sequence(tmp_path / "seq", camera_view_of_patterns(64, 32), ps)
    assert _files.procam_wrote(frames[0])  # listed as a frame by its folder's manifest
    (tmp_path / "loose").mkdir()
    loose = Path(shutil.copy(frames[0], tmp_path / "loose" / frames[0].name))
    before = loose.read_bytes()
    assert not _files.procam_wrote(loose) and "is a frame of a capture" in _files.kept_because(loose)
    with pytest.raises(OutputError, match="is a frame of a capture"):
        io.write_image(loose, np.zeros((4, 4), np.uint8))
    assert loose.read_bytes() == before
    again = capture.write_sequence(tmp_path / "seq", camera_view_of_patterns(64, 32, seed=3), ps)  # its writer
    assert again == frames and frames[0].read_bytes() != before


def test_importing_the_file_plumbing_imports_no_format_code():
    import subprocess
    import sys

    code = ("import sys, procam.io.files; print(sorted(m for m in sys.modules if m.startswith('procam')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert eval(out) == ["procam", "procam.errors", "procam.io", "procam.io.files", "procam.io.formats",
                         "procam.io.image_marks", "procam.io.jsonfile"]


def test_a_hostile_manifest_or_json_output_is_read_as_not_procams_not_crashed(tmp_path):
    """Every JSON procam reads goes through the one bounded reader: a manifest nested 100,000 levels deep, or one
    with a key given twice, counts as no manifest, and such an output file as not procam's (never overwritten)."""
    from procam.io import files

    deep = "[" * 100_000 + "]" * 100_000
    (tmp_path / files.MANIFEST).write_text(deep)
    assert files.read_manifest(tmp_path) is None
    (tmp_path / files.MANIFEST).write_text('{"format": "procam-manifest", "files": {}, "files": {"a.png": "output"}}')
    assert files.read_manifest(tmp_path) is None
    out = tmp_path / "calib.json"
    out.write_text('{"format": "procam-calibration", "x": ' + deep + "}")
    assert not files.procam_wrote(out)


def test_read_image_refuses_what_is_not_a_readable_file_without_waiting(tmp_path):
    """A folder, a missing file, a dangling link, a named pipe (opened without blocking: never waited on) and an
    unreadable file each get a one-line error naming the file; a pipe has no PNG header."""
    import os

    from procam.errors import CaptureError

    (tmp_path / "dir.png").mkdir()
    (tmp_path / "link.png").symlink_to(tmp_path / "gone.png")
    cases = [("dir.png", "is a folder"), ("missing.png", "no such file"), ("link.png", "symbolic link to")]
    if hasattr(os, "mkfifo"):
        os.mkfifo(tmp_path / "pipe.png")
        cases.append(("pipe.png", "not a regular file"))
    if hasattr(os, "geteuid") and os.geteuid() != 0:  # root reads anything
        (tmp_path / "locked.png").write_bytes(b"\x89PNG")
        (tmp_path / "locked.png").chmod(0)
        cases.append(("locked.png", "cannot be read"))
    for name, words in cases:
        got = within(10, _images.read_image, tmp_path / name)
        assert isinstance(got, CaptureError) and str(got).startswith(str(tmp_path / name)) and words in str(got), name
    if hasattr(os, "mkfifo"):  # nor does the header of a pipe, read before a stack is made
        assert within(10, _images.png_header, tmp_path / "pipe.png") is None


@pytest.mark.skipif(not hasattr(__import__("os"), "mkfifo"), reason="no named pipes here")
def test_a_named_pipe_named_like_a_json_file_is_refused_not_waited_on(tmp_path):
    """A named pipe as a folder's manifest (the folder then counts as not procam's), or as any JSON file procam
    reads, answers at once (opening it blocked until a writer came: a command hung on a pose folder holding one)."""
    import errno
    import os

    from procam.io import jsonfile

    os.mkfifo(tmp_path / _files.MANIFEST)
    assert within(10, _files.read_manifest, tmp_path) is None
    got = within(10, jsonfile.load_json, tmp_path / _files.MANIFEST)
    assert isinstance(got, OSError) and got.errno == errno.EINVAL and "not a regular file" in str(got)
    (tmp_path / "dir.json").mkdir()
    assert isinstance(within(10, jsonfile.load_json, tmp_path / "dir.json"), IsADirectoryError)
    (tmp_path / "ok.json").write_text('{"a": [1, 2]}')
    assert jsonfile.load_json(tmp_path / "ok.json") == {"a": [1, 2]}


def test_read_image_reads_files_of_any_size_one_after_another(tmp_path):
    """Files read one after another: a file after a larger one, a larger after a smaller, 8- and 16-bit PNGs and
    JPEGs come out as OpenCV reads them, and a truncated JPEG or PNG is refused."""
    import cv2

    from procam.errors import CaptureError

    rng = np.random.default_rng(5)
    big = rng.integers(0, 256, (120, 160), np.uint8)
    files = {"big.png": big, "small.png": big[:9, :7].copy(), "deep.png": (big.astype(np.uint16) * 257)[:50],
             "photo.jpg": big}
    for name, img in files.items():
        assert cv2.imwrite(str(tmp_path / name), img)
    for name in ["big.png", "small.png", "deep.png", "small.png", "photo.jpg", "big.png"]:
        got = _images.read_image(tmp_path / name)
        want = cv2.imread(str(tmp_path / name), cv2.IMREAD_UNCHANGED)
        assert got.dtype == want.dtype and np.array_equal(got, want), name
    for name, what in (("photo.jpg", "no JPEG end marker"), ("big.png", "truncated")):
        data = (tmp_path / name).read_bytes()
        (tmp_path / f"cut-{name}").write_bytes(data[:len(data) * 2 // 3])
        with pytest.raises(CaptureError, match=what):
            _images.read_image(tmp_path / f"cut-{name}")
