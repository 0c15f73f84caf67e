"""Phase-family capture folders: patterns.json for every family, another tool's capture described by hand
(decoded and calibrated end to end), and a description that does not match its frames named as such."""

import functools
import json

import cv2
import numpy as np
import pytest

from procam import capture, patterns, pipeline, simulate, single_pose
from procam.board import Board
from procam.errors import CaptureError
from conftest import run_cli, verdict_warnings

#: The worked example of docs/patterns.md: "3-step columns then rows, a unit-frequency cue after each, no white or
#: black frame", with another tool's conventions (a sine, falling along the axis, shifted backwards, pixel centres at
#: i + 0.5, levels 1..255).
OTHER_TOOL = {"family": "phase", "width": 1920, "height": 1080,
              "fringe": {"sign": -1, "origin": 0, "pixel_center": 0.5, "shift": -1, "start": -1.5707963267948966,
                         "levels": [1, 255]},
              "sequence": [{"kind": "phase", "axis": "col", "steps": 3, "period": 120},
                           {"kind": "phase", "axis": "col", "steps": 3, "periods": 1},
                           {"kind": "phase", "axis": "row", "steps": 3, "period": 120},
                           {"kind": "phase", "axis": "row", "steps": 3, "periods": 1}]}


def other_tool_lines():
    """The other tool's 12 pattern lines, by its own formula ``128 + 127 sin(-2 pi (i + 0.5) / P - 2 pi k / 3)``
    (not by procam's generator): ``[(axis, values), ...]``."""
    out = []
    for axis, n in (("col", 1920), ("row", 1080)):
        i = np.arange(n)
        for period in (120, n):
            for k in range(3):
                out.append((axis, np.rint(128 + 127 * np.sin(-2 * np.pi * (i + 0.5) / period - 2 * np.pi * k / 3))))
    return out


@functools.lru_cache(maxsize=None)
def _paper_renderer():
    """The ``ideal`` rig (the paper's, with the single-pose method's assumptions true: the subject here is the
    description, not the method's model error) at 2x2 supersampling."""
    scene = simulate.preset("ideal").replace(supersample=2)
    return simulate.Renderer(scene), scene


def write_other_tool_capture(folder, description=None, lines=None, seed=0):
    """Render the other tool's sequence and write it as that tool would: img_1.png ... img_12.png (natural order),
    and the hand-written patterns.json."""
    r, scene = _paper_renderer()
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    for k, (axis, values) in enumerate(lines or other_tool_lines()):
        cv2.imwrite(str(folder / f"img_{k + 1}.png"), r.finish(r.linear_stripes(values, axis), rng))
    (folder / "patterns.json").write_text(json.dumps(description or OTHER_TOOL, indent=1))
    return scene


@pytest.fixture(scope="module")
def other_tool(tmp_path_factory):
    folder = tmp_path_factory.mktemp("other_tool") / "pose"
    scene = write_other_tool_capture(folder)
    return folder, scene


def test_the_description_is_procams_reading_of_the_other_tools_formula():
    ps = patterns.from_dict(OTHER_TOOL)
    assert ps.count == 12 and ps.white is None and ps.black is None
    for k, (axis, values) in enumerate(other_tool_lines()):
        got_axis, got = ps.line(k)
        assert got_axis == axis and np.abs(got.astype(int) - values).max() <= 1


def test_another_tools_capture_calibrates_end_to_end(other_tool, tmp_path):
    """No white frame, another frame order and phase convention, described only by the hand-written
    patterns.json: decode, corners from the mean of the fringes, single-pose calibration against the truth."""
    folder, scene = other_tool
    view, maps = pipeline.view_from_folder(folder, Board(10, 6, 24.0))
    assert maps.subpixel and view.valid.sum() >= 55
    truth = simulate.corner_truth(scene)
    err = np.linalg.norm(view.proj_pts - truth["projector"], axis=1)[view.valid]
    assert np.sqrt(np.mean(err ** 2)) < 0.1
    true = simulate.truth_calibration(scene)
    f_p = true.projector.K[0, 0]
    with verdict_warnings():  # the paper's method: on the ideal rig its projector assumptions hold
        calib = single_pose.calibrate(view, dense=None)
    assert calib.projector.K[0, 0] == pytest.approx(f_p, rel=0.01)
    assert calib.camera.K[0, 0] == pytest.approx(true.camera.K[0, 0], rel=0.01)
    # the default, as the CLI runs it: the dense samples (3 steps order no period on the dim wall, so the projector
    # is fitted from the board's samples alone, and its stated +- is wide): the truth within it
    code, out, err_text = run_cli(["calibrate", folder, "--board", "10x6", "--square", "24", "-o",
                                   tmp_path / "calib.json"])
    assert code in (0, 3), err_text
    saved = json.loads((tmp_path / "calib.json").read_text())
    assert abs(saved["projector"]["K"][0][0] - f_p) < 3.0 * saved["std"]["f_p"]
    assert saved["camera"]["K"][0][0] == pytest.approx(true.camera.K[0, 0], rel=0.01)


def _copy_with(folder, tmp_path, description):
    bad = tmp_path / "pose"
    bad.mkdir()
    for f in folder.glob("img_*.png"):
        (bad / f.name).write_bytes(f.read_bytes())
    (bad / "patterns.json").write_text(json.dumps(description))
    return bad


def test_a_wrong_shift_direction_is_named_with_the_change_that_fixes_it(other_tool, tmp_path):
    folder, _ = other_tool
    bad = _copy_with(folder, tmp_path, {**OTHER_TOOL, "fringe": {**OTHER_TOOL["fringe"], "shift": 1}})
    with pytest.raises(CaptureError, match="does not match the frames") as e:
        capture.load_capture(bad)
    assert "along the columns frames #0-#2 (column phase, period 120 px)" in str(e.value)
    assert 'with "shift": -1 (the phase steps the other way) in the column blocks they agree' in str(e.value)


def test_a_frame_of_the_other_axis_swapped_in_is_refused_not_decoded_to_nothing(other_tool, tmp_path):
    """A column frame and a row frame exchanged (two files renamed by hand) is refused in one line naming the frame
    order, and no change of the description is offered: one pixel "agreed at 100 %" with the column blocks' start
    turned, and was offered as the fix. (The bench's capture, whose fringes decode nowhere then, was decoded to
    0.0 % with exit 0: the next test.)"""
    folder, _ = other_tool
    bad = _copy_with(folder, tmp_path, OTHER_TOOL)
    first, seventh = (bad / "img_1.png").read_bytes(), (bad / "img_7.png").read_bytes()
    (bad / "img_1.png").write_bytes(seventh)
    (bad / "img_7.png").write_bytes(first)
    with pytest.raises(CaptureError, match=r"the description does not match the frames: along the columns .* — fix "
                                           r"patterns.json \(docs/patterns.md: the conventions and the frame order\)$"
                       ) as e:
        capture.load_capture(bad)
    assert " with " not in str(e.value).split("well-lit pixels")[1]  # no change of the description offered
    code, _, err = run_cli(["decode", bad, "-o", tmp_path / "maps.npz"])
    assert code == 2 and not (tmp_path / "maps.npz").exists() and "does not match the frames" in err


def test_a_capture_that_decodes_nowhere_is_refused_not_written(tmp_path):
    """A 3-step capture of one camera with no white or black frame, its first column frame and first row frame
    exchanged: no lit pixel decodes along either axis (every one's fringes too faint to order); written as 0.0 %
    decoded with exit 0 before, now a one-line error naming the frame order and the exposure."""
    from procam import simulate

    ps = patterns.pattern_set(1920, 1080, family="phase", steps=3, period=64, white_black=False)
    scene = simulate.with_board_pose(simulate.preset("paper"), simulate.RECOMMENDED_POSE)
    stack, truth = simulate.render(scene, order=ps, seed=7)
    folder = tmp_path / "pose"
    simulate.write_capture(folder, stack, truth, order=ps)
    first, row = ps.phase_blocks("col")[0].first, ps.phase_blocks("row")[0].first
    a, b = folder / f"{first:02d}.png", folder / f"{row:02d}.png"
    da, db = a.read_bytes(), b.read_bytes()
    a.write_bytes(db)
    b.write_bytes(da)
    with pytest.raises(CaptureError, match=r"0\.0% of the lit pixels decode along the columns .*the frame order in "
                                           r"patterns.json .* and the capture's exposure and focus"):
        capture.load_capture(folder)


def test_a_wrong_phase_sign_mirrors_the_coordinates_and_is_named(other_tool, tmp_path):
    """The columns' sign of the wrong way round is self-consistent (the column coordinates decode mirrored): the
    frames agree, the board comes out mirrored, and the message names the description's sign. (Both axes'
    signs wrong turn the projector's image by 180 degrees, which no frame and no orientation shows.)"""
    folder, _ = other_tool
    desc = json.loads(json.dumps(OTHER_TOOL))
    for block in desc["sequence"][:2]:
        block["sign"] = 1
    bad = _copy_with(folder, tmp_path, desc)
    with pytest.raises(CaptureError, match=r'mirror images.*"sign" in patterns.json'):
        pipeline.view_from_folder(bad, Board(10, 6, 24.0))


def test_a_wrong_period_is_named_by_the_frames_that_disagree(other_tool, tmp_path):
    folder, _ = other_tool
    desc = json.loads(json.dumps(OTHER_TOOL))
    desc["sequence"][2]["period"] = 96  # the rows' fringes are described with the wrong period
    bad = _copy_with(folder, tmp_path, desc)
    with pytest.raises(CaptureError, match=r"along the rows frames #6-#8 \(row phase, period 96 px\)"):
        capture.load_capture(bad)


def test_frames_that_are_not_fringes_are_named_by_their_modulation(tmp_path):
    """A 4-step description whose first block is in fact a flat grey frame repeated: almost no fringes."""
    lines = []
    for axis, n in (("col", 1920), ("row", 1080)):
        i = np.arange(n)
        for period in (120, n):
            for k in range(4):
                flat = axis == "row" and period == 120
                lines.append((axis, np.full(n, 128.0) if flat else
                              np.rint(127.5 + 127.5 * np.cos(2 * np.pi * (i + 0.5) / period + 2 * np.pi * k / 4))))
    desc = {"family": "phase", "width": 1920, "height": 1080,
            "sequence": [{"kind": "phase", "axis": a, "steps": 4, "period": p}
                         for a, n in (("col", 1920), ("row", 1080)) for p in (120, n)]}
    write_other_tool_capture(tmp_path / "pose", desc, lines)
    with pytest.raises(CaptureError, match=r"frames #8-#11 \(row phase, period 120 px\) show almost no fringes"):
        capture.load_capture(tmp_path / "pose")


def test_a_frame_out_of_place_is_named(tmp_path):
    """Frame #2 of a 4-step block is the block's frame #0 again (a repeated frame): the block is no sinusoid (with
    4 steps the one residual degree of freedom shows it in every frame; from 5 steps the frame itself is named)."""
    lines = []
    for axis, n in (("col", 1920), ("row", 1080)):
        i = np.arange(n)
        for period in (120, n):
            for k in range(4):
                lines.append((axis, np.rint(127.5 + 127.5 * np.cos(2 * np.pi * (i + 0.5) / period
                                                                  + 2 * np.pi * k / 4))))
    lines[2] = lines[0]
    desc = {"family": "phase", "width": 1920, "height": 1080,
            "sequence": [{"kind": "phase", "axis": a, "steps": 4, "period": p}
                         for a, n in (("col", 1920), ("row", 1080)) for p in (120, n)]}
    write_other_tool_capture(tmp_path / "pose", desc, lines)
    with pytest.raises(CaptureError, match=r"frames #0-#3 \(column phase, period 120 px\) do not make one sinusoid "
                                           r"of 4 steps"):
        capture.load_capture(tmp_path / "pose")


def test_gray_code_without_inverses_then_4_step_phase_decodes(tmp_path):
    """docs/patterns.md's second worked example, with procam's conventions, rendered and decoded."""
    desc = {"family": "gray-phase", "width": 1920, "height": 1080,
            "sequence": [{"kind": "gray", "axis": "col", "bits": 6, "inverse": False},
                         {"kind": "phase", "axis": "col", "steps": 4, "period": 32},
                         {"kind": "gray", "axis": "row", "bits": 6, "inverse": False},
                         {"kind": "phase", "axis": "row", "steps": 4, "period": 32},
                         {"kind": "white"}, {"kind": "black"}]}
    ps = patterns.from_dict(desc)
    assert ps.count == 22 and ps.white == 20
    r, scene = _paper_renderer()
    r = r.with_patterns(ps)
    rng = np.random.default_rng(2)
    folder = tmp_path / "pose"
    folder.mkdir()
    for k in range(ps.count):
        cv2.imwrite(str(folder / f"{k:02d}.png"), r.frame(k, rng))
    (folder / "patterns.json").write_text(json.dumps(desc))
    cap = capture.load_capture(folder)
    from procam import decode

    res = decode.decode(cap.stack, cap.pattern_set)
    tm = simulate.true_projector_maps(scene, step=4)
    got = res.col[::4, ::4]
    ok = tm.lit_board & np.isfinite(got)
    assert ok.sum() > 0.9 * tm.lit_board.sum()
    err = np.abs(got - tm.col)[ok]
    assert np.median(err) < 0.1 and np.mean(err > 8) < 2e-4  # sub-pixel, and (all but a few) in the right period


@pytest.mark.parametrize("family", ["phase", "heterodyne", "gray-phase"])
def test_patterns_json_round_trips_for_every_family(family, tmp_path):
    ps = patterns.pattern_set(640, 480, family=family)
    capture.write_sequence(tmp_path, patterns.frames(ps), ps)
    meta = json.loads((tmp_path / "patterns.json").read_text())
    assert meta["format"] == "procam-patterns" and meta["family"] == family and len(meta["files"]) == ps.count
    assert capture.resolve_pattern_set(tmp_path) == ps
    assert capture.resolve_pattern_set(tmp_path, projector=(ps.width, ps.height)) == ps  # --projector agrees
    with pytest.raises(CaptureError, match=f"made for a {ps.width}x{ps.height} projector"):
        capture.resolve_pattern_set(tmp_path, projector=(320, 240))  # contradicts it: the codes would be misread


@pytest.mark.parametrize("meta, words", [
    ({"family": "phase", "width": 64, "height": 48}, "no sequence"),
    ({"family": "phase", "width": 64, "height": 48, "sequence": [{"kind": "phase", "axis": "col", "steps": 4,
                                                                   "period": 8, "shfit": 1}]}, "unknown key 'shfit'"),
    ({"family": "phase", "width": 64, "height": 48, "sequence": [{"kind": "phase", "axis": "col", "steps": 2,
                                                                   "period": 8}]}, "steps must be from 3"),
    ({"family": "phase", "width": 64, "height": 48, "sequence": [
        {"kind": "phase", "axis": "col", "steps": 4, "period": p} for p in (8, 64)]}, "no phase block along the rows"),
    ({"family": "phase", "width": 64, "height": 48, "sequence": [
        {"kind": "phase", "axis": a, "steps": 4, "period": 8} for a in ("col", "row")]}, "unit-frequency cue"),
    ({"family": "heterodyne", "width": 700, "height": 48, "sequence": [
        {"kind": "phase", "axis": a, "steps": 4, "period": p} for a in ("col", "row") for p in (10, 11, 12)]},
     "beat to 660.0 px, less than the panel's 700"),
    ({"family": "heterodyne", "width": 256, "height": 48, "sequence": [  # counts 8, 7, 6: equal beats, none longer
        {"kind": "phase", "axis": a, "steps": 4, "periods": c} for a in ("col", "row") for c in (8, 7, 6)]},
     "give beats of 256.0 and 256.0 px: the second must be longer"),
    ({"family": "spiral", "width": 64, "height": 48}, "unknown family"),
    ({"family": "phase", "width": 64, "height": 48, "fringe": {"sign": 2}, "sequence": []}, "sign must be"),
])
def test_a_description_that_is_not_a_sequence_is_a_one_line_error(meta, words, tmp_path):
    (tmp_path / "patterns.json").write_text(json.dumps(meta))
    with pytest.raises(CaptureError, match=words):
        capture.resolve_pattern_set(tmp_path)


def test_frame_vocabulary_of_the_phase_families():
    ps = patterns.pattern_set(1920, 1080, family="gray-phase")
    g = ps.gray_block("col")
    assert capture.describe_frame(0, ps) == f"#0 (column Gray bit {g.bits - 1})"
    assert capture.describe_frame(1, ps) == f"#1 (column Gray bit {g.bits - 1} inverse)"
    assert capture.pair_role(1, ps) == ("inverse", 0)
    k = ps.phase_blocks("row")[0].first + 1
    assert capture.frame_role(k, ps) == "row phase 2 of 4, period 16 px"
    assert capture.frame_role(ps.white, ps) == "white" and capture.pair_role(ps.white, ps) == (None, None)
    cue = patterns.pattern_set(1920, 1080, family="phase").phase_blocks("col")[0]
    assert capture.frame_role(cue.first, patterns.pattern_set(1920, 1080, family="phase")).endswith(
        "the unit-frequency cue")


def test_default_sequences_have_a_middle_level_and_eight_steps(tmp_path):
    """The defaults keep the dim wall behind the board (benchmarks/phase.py): phase has a 128-px level between its
    16-px fringes and the cue, the heterodyne 8 steps; one --period gives one level under the cue."""
    ps = patterns.pattern_set(1920, 1080, family="phase")
    assert [(b.period, b.steps) for b in ps.phase_blocks("col")] == [(1920, 8), (128, 8), (16, 8)]
    assert [b.period for b in ps.phase_blocks("row")] == [1152, 128, 16]  # the cue a whole number of 128 px
    assert ps.count == 50
    het = patterns.pattern_set(1920, 1080, family="heterodyne")
    assert {b.steps for b in het.blocks if b.kind == "phase"} == {8} and het.count == 50
    assert patterns.pattern_set(1920, 1080, family="gray-phase").count == 42  # unchanged: 4 steps at 16 px
    code, out, _ = run_cli(["patterns", "-p", "320x240", "-o", tmp_path / "one", "--family", "phase", "--period", "40"])
    assert code == 0 and "columns 8 steps at 40 px + 8 steps at 320 px;" in out
    code, out, _ = run_cli(["patterns", "-p", "320x240", "-o", tmp_path / "dflt", "--family", "phase"])
    assert code == 0 and "columns 8 steps at 16 px + 8 steps at 128 px + 8 steps at 384 px;" in out


def test_a_missing_frame_is_counted_against_the_description(tmp_path):
    ps = patterns.pattern_set(320, 240, family="heterodyne", steps=3)
    capture.write_sequence(tmp_path, patterns.frames(ps), ps)
    (tmp_path / "05.png").unlink()
    with pytest.raises(CaptureError, match=r"expected 20 images for the sequence its patterns.json describes "
                                           r"\(heterodyne: columns 3 steps.*found 19 — 05.png"):
        capture.load_capture(tmp_path)


def test_cli_patterns_and_simulate_write_a_phase_family(tmp_path):
    code, out, _ = run_cli(["patterns", "-p", "320x240", "-o", tmp_path / "pats", "--family", "gray-phase",
                            "--steps", "3", "--no-inverse"])
    assert code == 0 and "gray-phase: columns Gray" in out
    written = patterns.from_dict(json.loads((tmp_path / "pats" / "patterns.json").read_text()))
    assert written == patterns.pattern_set(320, 240, family="gray-phase", steps=3, inverse=False)
    assert len(list((tmp_path / "pats").glob("pattern_*.png"))) == written.count
    code, out, err = run_cli(["patterns", "-p", "320x240", "-o", tmp_path / "p2", "--steps", "3"])
    assert code == 2 and "--steps applies to the phase families" in err
    code, out, err = run_cli(["patterns", "-p", "320x240", "-o", tmp_path / "p3", "--family", "heterodyne",
                              "--counts", "7,6"])
    assert code == 2 and "--counts must be three numbers" in err


@pytest.mark.parametrize("command", ["patterns", "simulate"])
@pytest.mark.parametrize("args, phrase", [
    (["--no-white-black"], "--no-white-black applies to the phase families, not to --family gray"),
    (["--white-black"], "--white-black applies to the phase families"),
    (["--no-complementary"], "--no-complementary applies to --family gray-phase, not to --family gray"),
    (["--family", "phase", "--no-inverse"], "--no-inverse applies to --family gray-phase, not to --family phase"),
    (["--family", "heterodyne", "--complementary"], "--complementary applies to --family gray-phase"),
    (["--family", "phase", "--order", "moreno"], "--order applies to the Gray family"),
    (["--family", "phase", "--order", "opencv"], "--order applies to the Gray family"),
    (["--family", "gray-phase", "--counts", "7,6,5"], "--counts applies to --family heterodyne"),
    (["--family", "heterodyne", "--period", "16"], "the heterodyne's periods are given as --counts"),
    (["--period", "16"], "--period applies to --family phase or gray-phase, not to --family gray"),
])
def test_an_option_of_another_family_is_refused_not_ignored(command, args, phrase, tmp_path):
    """Every family-specific pattern option given with a family it does not apply to is a one-line error before
    anything is written (an option that changes nothing and exits 0 would let the user believe it did)."""
    where = ["-p", "320x240", "-o", tmp_path / "out"] if command == "patterns" else [tmp_path / "out"]
    code, out, err = run_cli([command, *where, *args])
    assert code == 2 and phrase in err and len(err.strip().splitlines()) == 1, err
    assert list(tmp_path.iterdir()) == []


def test_an_option_of_its_own_family_is_taken(tmp_path):
    """The same options with their own family change the sequence."""
    for args, want in ((["--family", "phase", "--no-white-black"], patterns.pattern_set(320, 240, family="phase",
                                                                                          white_black=False)),
                       (["--family", "gray-phase", "--no-complementary"],
                        patterns.pattern_set(320, 240, family="gray-phase", complementary=False)),
                       (["--order", "moreno"], patterns.pattern_set(320, 240, "moreno"))):
        out = tmp_path / "_".join(a.strip("-") for a in args)
        code, _, err = run_cli(["patterns", "-p", "320x240", "-o", out, *args])
        assert code == 0, err
        assert patterns.from_dict(json.loads((out / "patterns.json").read_text())) == want
