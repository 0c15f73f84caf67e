import json
import shutil

import cv2
import numpy as np
import pytest
from conftest import camera_view_of_patterns, run_cli, write_stack

from procam import capture, patterns
from procam.errors import CaptureError, OutputError, ProcamError
from procam.io import files as _files
from procam.io import images as _images

W, H = 64, 48  # projector; the 'camera' sees it pixel for pixel


@pytest.fixture
def pose(tmp_path):
    write_stack(tmp_path / "pose", camera_view_of_patterns(W, H))
    return tmp_path / "pose"


def test_natural_sort_and_any_names(tmp_path):
    st = camera_view_of_patterns(W, H)
    names = [f"img{i}.png" for i in range(len(st))]  # img2 must come before img10
    write_stack(tmp_path, st, names)
    (tmp_path / "notes.txt").write_text("not an image")
    files = _files.list_images(tmp_path)
    assert [f.name for f in files] == names
    cap = capture.load_capture(tmp_path, (W, H))
    assert np.array_equal(cap.stack, st)


def test_natural_order_reads_decimal_digits_of_any_script_and_nothing_else():
    """Runs of decimal digits (Arabic-Indic ones too) are numbers; a superscript or circled digit is text, not an
    internal error (``int('\u00b2')`` raises)."""
    names = ["img10.png", "\u00b21.png", "img2.png", "1\u00b22.png", "\u2460.png", "img\u0663.png", "IMG1.png"]
    assert sorted(names, key=_files.natural_key) == ["1\u00b22.png", "IMG1.png", "img2.png", "img\u0663.png",
                                                     "img10.png", "\u00b21.png", "\u2460.png"]


def test_colour_and_16bit_images_decode(tmp_path):
    from procam import decode

    st8 = camera_view_of_patterns(W, H, seed=1)
    colour = np.repeat(st8[..., None], 3, axis=3)
    write_stack(tmp_path / "colour", colour)
    st16 = camera_view_of_patterns(W, H, seed=1, dtype=np.uint16)
    write_stack(tmp_path / "sixteen", st16)
    yy, xx = np.mgrid[:H, :W]
    for sub in ("colour", "sixteen"):
        cap = capture.load_capture(tmp_path / sub, (W, H))
        r = decode.decode(cap.stack, cap.pattern_set)
        assert np.array_equal(r.col, xx) and np.array_equal(r.row, yy), sub
    assert capture.load_capture(tmp_path / "sixteen", (W, H)).stack.dtype == np.uint16


def test_wrong_count(pose):
    (sorted(pose.iterdir())[-1]).unlink()
    with pytest.raises(CaptureError, match=r"expected 26 images for a 64x48 projector.*found 25"):
        capture.load_capture(pose, (W, H))
    code, out, err = run_cli(["decode", pose, "--projector", f"{W}x{H}"])
    assert code == 2 and "expected 26 images" in err and "found 25" in err and "Traceback" not in err


def test_wrong_count_for_a_projector_too_small_for_every_step(pose):
    """The count's hint tries --step 2, 3, 4 and 8; for an 8x8 projector most of them leave fewer than 2 codes per
    axis: the hint skips them, and the error is the count, exit 2 (it was an internal error)."""
    with pytest.raises(CaptureError, match=r"expected 14 images for a 8x8 projector.*found 26"):
        capture.load_capture(pose, (8, 8))
    code, out, err = run_cli(["decode", pose, "--projector", "8x8"])
    assert code == 2 and "expected 14 images" in err and "internal error" not in err


def test_missing_white_black_hint(tmp_path):
    write_stack(tmp_path, camera_view_of_patterns(W, H)[:-2])
    with pytest.raises(CaptureError, match="two short: the white and black frames seem to be missing"):
        capture.load_capture(tmp_path, (W, H))


def test_two_short_for_a_projector_one_pixel_too_wide_names_the_common_size_too(tmp_path):
    """A 1024x768 capture read as 1025x768 is two frames short too (one more column bit): the hint names the size
    that fits before the missing white and black (which only it blamed, wrongly)."""
    from procam import patterns as P

    ps = P.pattern_set(1024, 768)
    write_stack(tmp_path, np.zeros((ps.count, 4, 4), np.uint8))
    with pytest.raises(CaptureError, match="two short: that count fits a projector of 1024x768.*check --projector; "
                                           "or the white and black frames seem to be missing"):
        capture.load_capture(tmp_path, (1025, 768))


def test_wrong_projector_size_hint(tmp_path):
    write_stack(tmp_path, camera_view_of_patterns(W, H))
    with pytest.raises(CaptureError, match="found 26"):
        capture.load_capture(tmp_path, (1920, 1080))


def test_white_black_not_where_order_says(tmp_path):
    write_stack(tmp_path, camera_view_of_patterns(W, H, order="moreno"))
    with pytest.raises(CaptureError, match="pass --order moreno"):
        capture.load_capture(tmp_path, (W, H), "opencv")
    code, out, err = run_cli(["decode", tmp_path, "--projector", f"{W}x{H}"])
    assert code == 2 and "--order moreno" in err
    assert capture.load_capture(tmp_path, (W, H), "moreno").pattern_set.white == 0


def test_frame_levels_of_some_frames_are_those_of_all_frames():
    """check_white_black asks for the white and black frames' levels only: each frame's are the same bits as
    when every frame's are computed, and a capture whose white frame is not lit everywhere still fails."""
    from procam.capture.sample import _sample, frame_levels

    st = camera_view_of_patterns(W, H, seed=3)
    ps = patterns.pattern_set(W, H)
    sub = _sample(st)
    p5, p95 = frame_levels(st, sub)
    some = (ps.white, ps.black, 3, 0)
    q5, q95 = frame_levels(st, sub, frames=some)
    assert q5.tobytes() == p5[list(some)].tobytes() and q95.tobytes() == p95[list(some)].tobytes()
    assert p5[ps.white] > 0.5 and p95[ps.black] < 0.5 and not p5[3] > 0.5
    capture.check_white_black(st, ps, "pose", [f"{k:02d}.png" for k in range(len(st))])
    st[ps.white] = st[3]  # a pattern where the white frame belongs
    with pytest.raises(CaptureError, match="white and black frames are not where order 'opencv' puts them"):
        capture.check_white_black(st, ps, "pose", [f"{k:02d}.png" for k in range(len(st))])


def test_shuffled_frames(tmp_path):
    st = camera_view_of_patterns(W, H)
    st[[2, 4]] = st[[4, 2]]  # swap two pattern frames of different bits
    write_stack(tmp_path, st)
    with pytest.raises(CaptureError, match="do not look like a pattern and its inverse"):
        capture.load_capture(tmp_path, (W, H))


def test_mixed_sizes(pose):
    f = sorted(pose.iterdir())[5]
    cv2.imwrite(str(f), np.zeros((H + 2, W), np.uint8))
    with pytest.raises(CaptureError, match=f"{f.name}: size {W}x{H + 2} differs"):
        capture.load_capture(pose, (W, H))
    code, _, err = run_cli(["decode", pose, "--projector", f"{W}x{H}"])
    assert code == 2 and "differs" in err


def test_unreadable_file(pose):
    f = sorted(pose.iterdir())[3]
    f.write_bytes(b"this is not a png")
    with pytest.raises(CaptureError, match=f"{f.name}: cannot be read as an image"):
        capture.load_capture(pose, (W, H))
    code, _, err = run_cli(["decode", pose, "--projector", f"{W}x{H}"])
    assert code == 2 and "cannot be read" in err


def test_empty_and_missing_folder(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(CaptureError, match="no images found"):
        capture.load_capture(tmp_path / "empty", (W, H))
    code, _, err = run_cli(["decode", tmp_path / "empty", "--projector", f"{W}x{H}"])
    assert code == 2 and "no images found" in err
    code, _, err = run_cli(["decode", tmp_path / "nope", "--projector", f"{W}x{H}"])
    assert code == 2 and "no such folder" in err


def test_projector_size_from_patterns_json(tmp_path):
    ps = patterns.pattern_set(W, H)
    write_stack(tmp_path, camera_view_of_patterns(W, H))
    _files.write_text(tmp_path / "patterns.json", __import__("json").dumps(ps.to_dict()))
    assert capture.load_capture(tmp_path).pattern_set == ps
    shutil.move(tmp_path / "patterns.json", tmp_path.parent / "elsewhere.json")
    with pytest.raises(CaptureError, match="pass --projector"):
        capture.load_capture(tmp_path)


def test_cli_decode_writes_maps_and_picture(pose, tmp_path):
    code, out, err = run_cli(["decode", pose, "--projector", f"{W}x{H}", "-o", tmp_path / "maps.npz",
                              "--png", tmp_path / "d.png"])
    assert code == 0, err
    with np.load(tmp_path / "maps.npz") as m:
        col, row = m["col"], m["row"]
    yy, xx = np.mgrid[:H, :W]
    assert np.array_equal(col, xx) and np.array_equal(row, yy)
    img = cv2.imread(str(tmp_path / "d.png"))
    assert img is not None and img.shape[1] > 500
    assert not list(tmp_path.glob(".*tmp*"))


def test_cli_patterns_roundtrip(tmp_path):
    code, out, err = run_cli(["patterns", "--projector", "1280x720", "-o", tmp_path / "p"])
    assert code == 0, err
    files = _files.list_images(tmp_path / "p")
    assert len(files) == 44
    st = _images.read_images(files)
    assert np.array_equal(st, patterns.generate(1280, 720))
    code, _, err = run_cli(["patterns", "--projector", "1280x720", "-o", tmp_path / "q", "--order", "zigzag"])
    assert code == 2 and "--order" in err


def test_saturated_and_dark_frames(tmp_path):
    st = camera_view_of_patterns(W, H)
    over = np.clip(st.astype(int) * 3, 0, 255).astype(np.uint8)  # white frame clipped at 255
    write_stack(tmp_path / "over", over)
    cap = capture.load_capture(tmp_path / "over", (W, H))
    assert any("saturated" in w and "reduce the exposure" in w for w in cap.warnings)
    blown = np.full_like(st, 255)
    blown[:, :, : W // 4] = st[:, :, : W // 4]
    write_stack(tmp_path / "blown", blown)
    with pytest.raises(CaptureError, match="black frame is saturated"):
        capture.load_capture(tmp_path / "blown", (W, H), check=True)
    dark = np.full_like(st, 12)
    write_stack(tmp_path / "dark", dark)
    with pytest.raises(CaptureError, match="projector's light is not visible"):
        capture.load_capture(tmp_path / "dark", (W, H))


def test_step_hint_and_step_capture(tmp_path):
    from procam import decode

    w, h, step = 96, 64, 2
    light = patterns.generate(w, h, step=step).astype(np.float32)
    write_stack(tmp_path, np.clip(20 + 0.7 * light, 0, 255).astype(np.uint8))
    with pytest.raises(CaptureError, match="--step 2"):
        capture.load_capture(tmp_path, (w, h))
    cap = capture.load_capture(tmp_path, (w, h), step=step)
    r = decode.decode(cap.stack, cap.pattern_set)
    yy, xx = np.mgrid[:h, :w]
    assert np.array_equal(r.col, xx // 2 * 2 + 0.5) and np.array_equal(r.row, yy // 2 * 2 + 0.5)
    code, _, err = run_cli(["decode", tmp_path, "--projector", f"{w}x{h}", "--step", "2"])
    assert code == 0, err


def test_write_sequence_writes_pngs_and_json(tmp_path):
    import cv2

    ps = patterns.pattern_set(37, 19)
    st = patterns.generate(37, 19)
    paths = capture.write_sequence(tmp_path, st, ps, prefix="pattern_")
    assert [p.name for p in paths][:2] == ["pattern_00.png", "pattern_01.png"]
    meta = json.loads((tmp_path / "patterns.json").read_text())
    assert meta["count"] == 24 and meta["white"] == 22 and meta["order"] == "opencv"
    for p, img in zip(paths, st):
        assert np.array_equal(cv2.imread(str(p), cv2.IMREAD_UNCHANGED), img)
    assert not list(tmp_path.glob("*.tmp*"))


def test_write_sequence_removes_stale_frames_of_a_longer_sequence(tmp_path):
    big = patterns.pattern_set(640, 480)
    capture.write_sequence(tmp_path, patterns.generate(640, 480), big, prefix="pattern_")
    (tmp_path / "notes.png").write_bytes(b"")
    (tmp_path / "pattern_a.png").write_bytes(b"")
    small = patterns.pattern_set(37, 19)
    with pytest.raises(OutputError, match="2 file.s. procam did not write .notes.png, pattern_a.png.*--force"):
        capture.write_sequence(tmp_path, patterns.generate(37, 19), small, prefix="pattern_")
    paths = capture.write_sequence(tmp_path, patterns.generate(37, 19), small, prefix="pattern_", force=True)
    left = sorted(p.name for p in tmp_path.glob("pattern_*.png"))
    assert big.count > small.count and left == sorted([p.name for p in paths] + ["pattern_a.png"])
    assert (tmp_path / "notes.png").exists()
    assert capture.remove_stale(tmp_path, paths, prefix="pattern_") == []


def test_check_pairs_names_frames_in_the_one_vocabulary(tmp_path):
    st = camera_view_of_patterns(W, H)
    st[[2, 4]] = st[[4, 2]]  # #2 is column bit 4 (of 6, counted from the least significant), #4 column bit 3
    write_stack(tmp_path, st)
    with pytest.raises(CaptureError, match=r"images #2 \(02.png\) and #3 \(03.png\) do not look like a pattern and its "
                                           r"inverse \(column bit 4, correlation"):
        capture.load_capture(tmp_path, (W, H))
    ps = patterns.pattern_set(W, H)
    assert capture.describe_frame(2, ps) == "#2 (column bit 4)" and capture.frame_role(3, ps) == "column bit 4 inverse"
    assert capture.pair_role(3, ps) == ("inverse", 2) and capture.pair_role(ps.white, ps) == (None, None)
    assert capture.describe_frame("pre-flight white", ps) == "pre-flight white"


def _manifest(folder) -> dict:
    return json.loads((folder / _files.MANIFEST).read_text())["files"]


def test_one_writer_writes_a_camera_capture_whole_or_not_at_all(tmp_path):
    """The capture loop's writer: frames go into a hidden partial folder that becomes the pose folder only when
    complete, with the manifest roles 'captured' and 'sidecar'; an error leaves nothing (or, kept, says where)."""
    ps = patterns.pattern_set(37, 19)
    st = patterns.generate(37, 19)
    out = tmp_path / "pose"
    with capture.SequenceWriter(out, ps, writer="capture", captured=True, sidecars=["capture.json"]) as w:
        for k in range(ps.count):
            w.add(k, st[k])
        assert w.folder.name.startswith(".pose.partial-") and not out.exists()
        paths = w.finish({"capture.json": "{}"})
    assert paths[0] == out / "00.png" and [p.name for p in tmp_path.iterdir()] == ["pose"]
    roles = _manifest(out)
    assert {roles[p.name] for p in paths} == {"captured"}
    assert roles["patterns.json"] == roles["capture.json"] == "sidecar"
    assert json.loads((out / "patterns.json").read_text())["files"] == [p.name for p in paths]
    assert np.array_equal(capture.load_capture(out).stack, st)
    # procam never writes into a capture
    with pytest.raises(ProcamError, match="exists and is not empty"):
        capture.SequenceWriter(out, ps, writer="capture", captured=True).open()
    with pytest.raises(OutputError, match="holds a camera capture"):
        capture.write_sequence(out, st, ps, force=True)
    # an error inside: nothing is left; with keep_failed the hidden partial folder stays and the message says where
    with pytest.raises(ProcamError, match="^boom$"):
        with capture.SequenceWriter(tmp_path / "a", ps, writer="capture", captured=True) as w:
            w.add(0, st[0])
            raise ProcamError("boom")
    with pytest.raises(ProcamError, match=r"^boom — the frames so far are in .*\.b\.partial-"):
        with capture.SequenceWriter(tmp_path / "b", ps, writer="capture", captured=True, keep_failed=True) as w:
            w.add(0, st[0])
            raise ProcamError("boom")
    assert sorted(p.name for p in tmp_path.iterdir())[0].startswith(".b.partial-")
    assert sorted(p.name for p in tmp_path.iterdir())[1:] == ["pose"]


def test_a_complete_capture_whose_folder_was_taken_meanwhile_is_kept(tmp_path):
    ps = patterns.pattern_set(37, 19)
    st = patterns.generate(37, 19)
    w = capture.SequenceWriter(tmp_path / "pose", ps, writer="capture", captured=True)
    with pytest.raises(ProcamError, match="something was written into it during the capture; the capture is in"):
        with w:
            for k in range(ps.count):
                w.add(k, st[k])
            (tmp_path / "pose").mkdir()
            (tmp_path / "pose" / "mine.txt").write_text("mine")
            w.finish()
    assert [p.name for p in (tmp_path / "pose").iterdir()] == ["mine.txt"]
    assert np.array_equal(capture.load_capture(w.folder).stack, st)  # complete, under its hidden name
