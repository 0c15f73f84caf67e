"""patterns.json and rig.json as a careless or unlucky user writes them (issue 36, items 13, 14, 16): every number
and every JSON structure bounded before use, unknown keys named with the closest known one, a rig folder without
rig.json named as such; each a one-line error naming the file and the field, exit code 2 on the command line."""

import json

import numpy as np
import pytest

from procam import capture, patterns
from procam.errors import CaptureError
from conftest import run_cli, write_stack

GRAY_PHASE = {"family": "gray-phase", "width": 64, "height": 48, "sequence": [
    {"kind": "gray", "axis": "col", "bits": 3}, {"kind": "phase", "axis": "col", "steps": 4, "period": 8},
    {"kind": "gray", "axis": "row", "bits": 3}, {"kind": "phase", "axis": "row", "steps": 4, "period": 8}]}


def _with(path, text):
    path.mkdir(parents=True, exist_ok=True)
    (path / "patterns.json").write_text(text if isinstance(text, str) else json.dumps(text))
    return path


def _block(i, **change):
    doc = json.loads(json.dumps(GRAY_PHASE))
    doc["sequence"][i].update(change)
    return doc


@pytest.mark.parametrize("text, words", [
    # a Gray block before its phase block used that block's period unchecked (ZeroDivisionError, TypeError)
    (_block(1, period=None) | {"sequence": [GRAY_PHASE["sequence"][0],
                                            {"kind": "phase", "axis": "col", "steps": 4, "periods": 0},
                                            *GRAY_PHASE["sequence"][2:]]},
     r"patterns.json: sequence\[1\].periods must be from 1e-06 to 32, got 0"),
    (_block(1, period=[16]), r"patterns.json: sequence\[1\].period must be a number, got \[16\]"),
    # a 400-digit width overflowed every float conversion (OverflowError)
    ('{"width": ' + "9" * 400 + ', "height": 48}', r"patterns.json: width is a whole number of 400 digits"),
    ('{"family": "phase", "width": ' + "9" * 400 + ', "height": 48, "sequence": []}',
     r"patterns.json: width is a whole number of 400 digits"),
    ('{"width": 64, "height": 48, "step": 1e400}', r"patterns.json: step is inf, not a finite number"),
    ({"width": 64, "height": 48, "step": 10 ** 12}, r"patterns.json: step must be from 1 to 64"),
    # nested 100,000 levels deep (RecursionError), and 70 levels (under Python's limit, over procam's)
    ("[" * 100000 + "]" * 100000, r"patterns.json: is nested too deep \(more than 64 levels"),
    ('{"width": 64, "height": 48, "notes": ' + "[" * 70 + "]" * 70 + "}", r"patterns.json: is nested too deep"),
    ("[1, 2]", r"patterns.json: not a JSON object"),
    ({"width": 64, "height": 48, "bit_order": "reversed"}, r'patterns.json: bit_order must be "msb-first"'),
    (GRAY_PHASE | {"upside_down": 1}, r"patterns.json: upside_down must be true or false, got 1"),
    (GRAY_PHASE | {"upside_down": True}, r"patterns.json: upside_down applies to a sequence without a Gray code"),
], ids=["periods-0", "period-list", "width-400-digits-gray", "width-400-digits-phase", "step-1e400", "step-1e12",
        "nested-100000", "nested-70", "not-an-object", "bit-order", "upside-down-1", "upside-down-gray"])
def test_every_number_and_structure_is_bounded_before_use(tmp_path, text, words):
    folder = _with(tmp_path / "pose", text)
    with pytest.raises(CaptureError, match=words):
        capture.resolve_pattern_set(folder)


@pytest.mark.parametrize("change, words", [
    ({"count": 40}, r"count 40 is not that of the 64x48 sequence of order opencv, step 1 \(26\)"),
    ({"col_bits": 9}, r"col_bits 9 is not that of"), ({"col_offset": 64}, r"col_offset 64 is not that of"),
    ({"white": 25, "black": 24}, r"white 25 is not that of"),
])
def test_what_a_gray_description_states_must_be_its_sequences(tmp_path, change, words):
    """count, bits, offsets, white and black follow from width, height, order and step: a file that states others
    describes another sequence, and was read as procam's with exit 0 (the key silently ignored)."""
    doc = {**patterns.pattern_set(64, 48).to_dict(), **change}
    with pytest.raises(CaptureError, match=words):
        capture.resolve_pattern_set(_with(tmp_path / "pose", doc))
    ok = patterns.pattern_set(64, 48).to_dict()
    assert capture.resolve_pattern_set(_with(tmp_path / "same", ok)) == patterns.pattern_set(64, 48)
    assert capture.resolve_pattern_set(tmp_path / "pose", order="moreno").order == "moreno"  # --order: another one


@pytest.mark.parametrize("doc, words", [
    # the typo made the file a Gray description: "unknown order 'procam'; fix it or pass --order"
    ({**GRAY_PHASE, "famliy": "gray-phase", "order": "procam"} | {"family": None},
     r"unknown key 'famliy' \(did you mean 'family'\?"),
    ({k: v for k, v in GRAY_PHASE.items() if k != "family"} | {"famliy": "gray-phase", "order": "procam"},
     r"unknown key 'famliy' \(did you mean 'family'\?"),
    ({"width": 64, "height": 48, "setp": 2}, r"unknown key 'setp' \(did you mean 'step'\?"),
    ({"width": 64, "height": 48, "sequence": []}, r"'sequence' belongs to a phase family's description, but the file "
                                                   r"names no family .* add \"family\" \(phase, heterodyne"),
    ({"family": "gray", "width": 64, "height": 48, "sequence": []}, r"unknown key 'sequence' \(the keys of a "
                                                                     r"Gray-code description"),
    (_block(0, bitorder="lsb-first"), r"sequence\[0\]: unknown key 'bitorder' \(did you mean 'bit_order'\?"),
    (GRAY_PHASE | {"fringe": {"shfit": -1}}, r"fringe: unknown key 'shfit' \(did you mean 'shift'\?"),
], ids=["famliy", "famliy-alone", "setp", "no-family-with-sequence", "gray-with-sequence", "bitorder", "shfit"])
def test_an_unknown_key_is_named_with_the_closest_known_one(tmp_path, doc, words):
    doc = {k: v for k, v in doc.items() if v is not None}
    folder = _with(tmp_path / "pose", doc)
    with pytest.raises(CaptureError, match=words) as e:
        capture.resolve_pattern_set(folder)
    assert "unknown order" not in str(e.value)  # the key is the cause named, not the order it left alone


def test_the_loader_names_the_field_and_leaves_ordinary_documents_alone():
    from procam.io.jsonfile import JSONError, loads

    assert loads('{"a": [1, 2.5, {"b": -3}], "c": "x"}') == {"a": [1, 2.5, {"b": -3}], "c": "x"}
    with pytest.raises(JSONError, match=r"a\[2\]\.b is a whole number of 20 digits"):
        loads('{"a": [1, 2, {"b": -12345678901234567890}]}')
    with pytest.raises(JSONError, match=r"x is nan, not a finite number"):
        loads('{"x": NaN}')
    assert np.isnan(loads('{"x": NaN}', finite=False)["x"])


def test_cli_refuses_a_bad_description_with_exit_2_and_the_field(tmp_path):
    folder = _with(tmp_path / "pose", ('{"family": "phase", "width": ' + "9" * 400 + ', "height": 48, "sequence": []}'))
    write_stack(folder, np.zeros((4, 8, 8), np.uint8))
    code, out, err = run_cli(["decode", folder, "-o", tmp_path / "maps.npz"])
    assert code == 2, out + err
    text = " ".join((out + err).split())
    assert "patterns.json: width is a whole number of 400 digits" in text and "Traceback" not in text
    assert not (tmp_path / "maps.npz").exists()


def test_a_deep_rig_json_is_a_one_line_error(tmp_path):
    rig = tmp_path / "rig"
    for sub in ("left", "right"):
        (rig / sub).mkdir(parents=True)
        (rig / sub / "patterns.json").write_text('{"width": 64, "height": 48}')
    (rig / "rig.json").write_text('{"format": "procam-rig-pose", "pairs": ' + "[" * 100000 + "]" * 100000 + "}")
    with pytest.raises(CaptureError, match=r"rig.json: not a readable rig manifest: it is nested too deep"):
        capture.read_rig_pose(rig)


def test_a_rig_folder_without_rig_json_names_what_a_rig_needs(tmp_path):
    rig = tmp_path / "rig"
    for sub in ("left", "right"):
        write_stack(rig / sub, np.zeros((3, 8, 8), np.uint8))
    with pytest.raises(CaptureError, match=r"holds no images, but its sub-folders left, right do: a rig pose folder "
                                           r"needs a rig.json .* or a patterns.json in every sub-folder"):
        capture.load_capture(rig, projector=(64, 48))
    with pytest.raises(CaptureError, match=r"needs a rig.json"):
        capture.read_rig_pose(rig)
    code, out, err = run_cli(["decode", rig, "--projector", "64x48", "-o", tmp_path / "maps.npz"])
    assert code == 2 and "rig.json" in " ".join((out + err).split())


# ------------------------------------------------------------------------------------------------------------------
# the order of a Gray block's bits (issue 36 item 8, issue 34 build item 2)

GRAY_BLOCKS = {"gray-opencv": dict(order="opencv"), "gray-moreno": dict(order="moreno"),
               "gray-phase": dict(family="gray-phase"),
               "gray-phase-no-inverse": dict(family="gray-phase", inverse=False, complementary=False)}


def _render_gray_blocks(tmp_path, kind, rendered, described):
    """The small scene's capture of the sequence ``kind`` with its Gray bits in the order ``rendered``, written with
    a patterns.json that says ``described``; returns (folder, scene)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from sim_small import small_scene

    from procam import patterns, simulate

    scene = small_scene()
    ps = patterns.pattern_set(*scene.proj_size, bit_order=rendered, **GRAY_BLOCKS[kind])
    r = simulate.Renderer(scene).with_patterns(ps)
    rng = np.random.default_rng(5)
    folder = tmp_path / f"{kind}-{rendered}-{described}"
    write_stack(folder, np.stack([r.frame(k, rng) for k in range(ps.count)]))
    meta = ps.to_dict()
    for d in [meta, *meta.get("sequence", [])]:
        if d is meta and "sequence" in meta or d.get("kind", "gray") != "gray":
            continue
        d.pop("bit_order", None)
        if described != "msb-first":
            d["bit_order"] = described
    (folder / "patterns.json").write_text(json.dumps(meta))
    return folder, scene


@pytest.mark.parametrize("kind", list(GRAY_BLOCKS))
@pytest.mark.parametrize("rendered", ["msb-first", "lsb-first"])
def test_every_gray_block_decodes_in_the_order_described(tmp_path, kind, rendered):
    from procam import decode, simulate

    folder, scene = _render_gray_blocks(tmp_path, kind, rendered, rendered)
    cap = capture.load_capture(folder)
    assert cap.pattern_set.count == len(cap.files)
    res = decode.decode(cap.stack, cap.pattern_set)
    tm = simulate.true_projector_maps(scene, step=4)
    for got, true in ((res.col[::4, ::4], tm.col), (res.row[::4, ::4], tm.row)):
        ok = tm.lit_board & np.isfinite(got)
        assert ok.sum() > 0.9 * tm.lit_board.sum()
        err = np.abs(got - true)[ok]
        assert np.median(err) < 0.6 and np.mean(err > 8) < 1e-3  # right to the pixel, no stripe out of place


@pytest.mark.parametrize("kind", list(GRAY_BLOCKS))
@pytest.mark.parametrize("rendered, described", [("lsb-first", "msb-first"), ("msb-first", "lsb-first")])
def test_a_gray_block_described_in_the_wrong_bit_order_is_refused_naming_the_order(tmp_path, kind, rendered,
                                                                                    described):
    folder, _ = _render_gray_blocks(tmp_path, kind, rendered, described)
    said, seen = ("most", "least") if described == "msb-first" else ("least", "most")
    where = "patterns.json" if kind.startswith("gray-o") or kind.startswith("gray-m") else r"sequence\[0\] in patterns.json"
    with pytest.raises(CaptureError, match=rf"the column Gray bits come {seen} significant first, the description "
                                           rf"says {said} .* write \"bit_order\": \"{rendered}\" in {where}"):
        capture.load_capture(folder)
    code, out, err = run_cli(["decode", folder, "-o", tmp_path / "maps.npz"])
    assert code == 2 and f'"bit_order": "{rendered}"' in " ".join((out + err).split())


def test_the_bit_order_check_on_integers_is_the_float_check_bit_for_bit():
    """The check reads an 8- or 16-bit capture's pattern/inverse pairs as integers and their 99th percentile off a
    histogram (issue 35: a third of its time), and samples 8-bit frames by a cast: the same densities as the float
    copies and np.percentile gave, and the same samples as numpy's slicing."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from sim_small import small_capture

    from procam import patterns
    from procam.capture import bit_order

    rng = np.random.default_rng(35)
    for n, top in [(1, 2), (2, 3), (7, 256), (1001, 256), (4096, 4), (5000, 65536), (99, 1)]:
        for _ in range(20):
            c = np.minimum(rng.integers(0, top, n), rng.integers(0, top))  # ties, and a cut that piles them up
            assert bit_order._percentile99_of_integers(c) == float(np.percentile(c.astype(np.float32), 99))
    scene, stack, _, _ = small_capture()
    ps = patterns.pattern_set(*scene.proj_size, "opencv")
    for axis in ("col", "row"):
        frames = bit_order._bits_in_described_order(ps, axis)[0]
        for st in (stack, stack.astype(np.uint16) * 257):
            for stride in (1, 2, 3, 4):  # 8-bit frames at 2 and 4 sampled by a cast, the others by numpy's slicing
                got = bit_order._edge_densities(st, frames, stride)
                want = bit_order._edge_densities(st.astype(np.float32), frames, stride)  # the float path
                assert np.isfinite(got).sum() >= 5 and np.array_equal(got, want, equal_nan=True)
    for shape in [(9, 16), (9, 17), (8, 24), (1, 8)]:
        img = rng.integers(0, 256, (2, *shape)).astype(np.uint8)[1]
        for stride in range(1, 10):
            got = bit_order._every(img, stride)
            assert got.flags.c_contiguous and np.array_equal(got, img[::stride, ::stride]), (shape, stride)


# ------------------------------------------------------------------------------------------------------------------
# the shift's direction, checked by the direction the fringes move (issue 36 item 5)

def _render_phase(tmp_path, name, description_change, **fringe):
    """The small scene's capture of procam's phase sequence (4 steps; shift +1, sign +1, or the conventions
    ``fringe``) with a patterns.json changed by ``description_change(meta)``; returns the folder."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from sim_small import small_scene

    from procam import patterns, simulate

    scene = small_scene()
    ps = patterns.pattern_set(*scene.proj_size, family="phase", steps=4, fringe=patterns.Fringe(**fringe))
    r = simulate.Renderer(scene).with_patterns(ps)
    rng = np.random.default_rng(7)
    folder = tmp_path / name
    write_stack(folder, np.stack([r.frame(k, rng) for k in range(ps.count)]))
    meta = ps.to_dict()
    description_change(meta)
    (folder / "patterns.json").write_text(json.dumps(meta))
    return folder


def _every_block(**change):
    def apply(meta):
        for b in meta["sequence"]:
            if b["kind"] == "phase":
                b.update(change)
    return apply


def test_a_shift_of_the_wrong_way_round_in_every_block_is_refused(tmp_path):
    """Frames shifted by +2 pi k / N described with "shift": -1 in every block: every frequency agrees, and the
    decoded projector image is turned by 180 degrees (the calibration then has the projector upside down)."""
    folder = _render_phase(tmp_path, "shift", _every_block(shift=-1))
    with pytest.raises(CaptureError, match=r"the projector's image decodes upside down in the camera \(turned by "
                                           r"1[5-8]\d degrees\), which is what \"shift\": -1 of the wrong way round in "
                                           r"every block does .* \"sign\": \+1 flipped in every block does the same\) — write \"shift\": \+1 "
                                           r"in every block"):
        capture.load_capture(folder)
    folder = _render_phase(tmp_path, "sign", _every_block(sign=-1))  # the same frames as a sign flipped everywhere
    with pytest.raises(CaptureError, match=r"decodes upside down in the camera"):
        capture.load_capture(folder)
    code, out, err = run_cli(["decode", folder, "-o", tmp_path / "maps.npz"])
    assert code == 2 and "upside down" in out + err and not (tmp_path / "maps.npz").exists()


def test_the_right_shift_passes_and_upside_down_is_said_not_guessed(tmp_path):
    right = _render_phase(tmp_path, "right", lambda meta: None)
    assert capture.load_capture(right).pattern_set.upside_down is False
    # a projector that really shows its image upside down says so (here: the same turned decode, described so)
    turned = _render_phase(tmp_path, "turned", lambda m: (_every_block(shift=-1)(m), m.update(upside_down=True)))
    assert capture.load_capture(turned).pattern_set.upside_down is True
    claimed = _render_phase(tmp_path, "claimed", lambda meta: meta.update(upside_down=True))
    with pytest.raises(CaptureError, match=r'says "upside_down": true, but the projector\'s image decodes upright'):
        capture.load_capture(claimed)


def test_a_cosine_described_for_a_sine_names_start(tmp_path):
    """Issue 34: the hint named shift, sign and axes, never ``start``.  Sine fringes (start -pi/2) described as
    procam's cosines."""
    folder = _render_phase(tmp_path, "sine", _every_block(start=0.0), start=-np.pi / 2)
    with pytest.raises(CaptureError, match=r'with "start": -1.5708 \(a sine where a cosine was said\) in the column '
                                           r"blocks they agree"):
        capture.load_capture(folder)


def test_missing_inverses_are_named(tmp_path):
    """Issue 34: a description without the inverse frames the tool has was refused without naming inverses."""
    folder, _ = _render_gray_blocks(tmp_path, "gray-phase", "msb-first", "msb-first")
    meta = json.loads((folder / "patterns.json").read_text())
    for b in meta["sequence"]:
        if b["kind"] == "gray":
            b["inverse"] = False
    meta.pop("count")
    (folder / "patterns.json").write_text(json.dumps(meta))
    with pytest.raises(CaptureError, match=r'found 42 — 16 more, one per Gray bit: the capture seems to show each '
                                           r'Gray bit with its inverse; say "inverse": true in sequence\[0\], '
                                           r'sequence\[2\]'):
        capture.load_capture(folder)


def test_an_output_folder_holding_a_deep_patterns_json_is_refused_not_crashed(tmp_path):
    """The output folder's check read a patterns.json there (an older procam's mark) unbounded: RecursionError."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "patterns.json").write_text("[" * 100000 + "]" * 100000)
    code, _, err = run_cli(["patterns", "-p", "64x48", "-o", out])
    assert code == 2 and "procam did not write (patterns.json)" in " ".join(err.split())
    assert (out / "patterns.json").read_text() == "[" * 100000 + "]" * 100000


def test_a_ceiling_mounted_projector_decodes_upside_down_rightly(tmp_path):
    """The ``ceiling`` rig's projector is rolled 180 degrees: procam's own phase capture of it passes as written;
    the same frames described by hand are refused until the description says ``"upside_down": true``."""
    from procam import patterns, simulate

    sc = simulate.preset("ceiling")
    K = np.array(sc.K_cam, float)
    K[:2] *= 0.5
    K[0, 2], K[1, 2] = (sc.K_cam[0][2] + 0.5) * 0.5 - 0.5, (sc.K_cam[1][2] + 0.5) * 0.5 - 0.5
    sc = sc.replace(cam_size=(640, 400), K_cam=K, supersample=1)
    ps = patterns.pattern_set(*sc.proj_size, family="phase", steps=4)
    r = simulate.Renderer(sc).with_patterns(ps)
    rng = np.random.default_rng(11)
    stack = np.stack([r.frame(k, rng) for k in range(ps.count)])
    for name, change in (("own", {}), ("by-hand", {"order": "custom"}),
                         ("by-hand-turned", {"order": "custom", "upside_down": True})):
        folder = tmp_path / name
        write_stack(folder, stack)
        (folder / "patterns.json").write_text(json.dumps(ps.to_dict() | change))
        if name == "by-hand":
            with pytest.raises(CaptureError, match="decodes upside down in the camera"):
                capture.load_capture(folder)
        else:
            assert capture.load_capture(folder).pattern_set.count == ps.count


def test_a_step_that_contradicts_the_description_is_refused(tmp_path):
    """patterns.json says step 1; --step 2 was read as another sequence, and the count message then blamed
    --projector, which was not given."""
    doc = patterns.pattern_set(64, 48).to_dict()
    with pytest.raises(CaptureError, match=r"--step 2: .*patterns.json says the sequence was made with step 1; "
                                           r"leave --step out"):
        capture.resolve_pattern_set(_with(tmp_path / "pose", doc), step=2)
    assert capture.resolve_pattern_set(tmp_path / "pose", step=1) == patterns.pattern_set(64, 48)
