"""A user's file is never lost (issue 36, items 1-4).

procam knows its own files by marks a user's file cannot carry by accident (a ``procam_format`` key or member, a
script's digest of itself: procam.io.formats), never by keys other tools write too; ``--force`` never overwrites
a file procam did not write; an output never lands on an input, nor on a file an input folder needs.  The last
test runs every writing command onto every kind of file a user owns and onto its own inputs, with and without
``--force``, and checks every byte survives.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import camera_view_of_patterns, run_cli
from test_bad_inputs import BOARD, render_pose, snapshot

from procam import io
from procam.io import files as _files


# ------------------------------------------------------------------------------------------------
# a user's own files, each looking like procam's by the rules before issue 36
def _storage(path: Path, keys: dict) -> None:
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for k, v in keys.items():
        fs.write(k, v)
    fs.release()


def user_file(path: Path, kind: str) -> Path:
    """Write a file of the user's of ``kind`` at ``path`` (what another tool, or the user, writes)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    K = np.array([[1000.0, 0, 640], [0, 1000, 400], [0, 0, 1]])
    if kind == "npz":      # their own remap tables and decoded maps: the members procam's have
        np.savez(path, map_x=np.zeros((4, 4), np.float32), map_y=np.ones((4, 4), np.float32),
                 col=np.zeros((4, 4)), valid_col=np.ones((4, 4), bool))
    elif kind == "yml":    # Moreno & Taubin's scan3d-capture writes these very keys
        _storage(path, {"cam_K": K, "proj_K": K, "R": np.eye(3), "T": np.ones((3, 1))})
    elif kind == "xml":    # kamino410's own calibration_result.xml
        _storage(path, {"img_shape": np.array([[800.0], [1280.0]]), "cam_int": K, "proj_int": K,
                        "rotation": np.eye(3), "translation": np.ones((3, 1))})
    elif kind == "py":     # the whole old mark, and even procam's new mark line with a wrong digest
        path.write_text("# procam-script sha256:0123\n# procam helpers of mine\nprint('mine')\n")
    elif kind == "json":
        path.write_text('{"mine": true, "cam_K": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}')
    elif kind == "html":
        path.write_text("<html><head><title>procam notes</title></head><body>procam</body></html>")
    elif kind == "png":
        _, buf = cv2.imencode(".png", np.full((8, 8), 7, np.uint8))
        path.write_bytes(buf.tobytes())
    elif kind == "jpg":
        _, buf = cv2.imencode(".jpg", np.full((8, 8, 3), 7, np.uint8))
        path.write_bytes(buf.tobytes())
    elif kind == "ply":
        path.write_text("ply\nformat ascii 1.0\ncomment procam-like scan of mine\nend_header\n")
    else:
        raise ValueError(kind)
    return path


KIND = {".npz": "npz", ".yml": "yml", ".yaml": "yml", ".xml": "xml", ".py": "py", ".json": "json", ".html": "html",
        ".png": "png", ".jpg": "jpg", ".ply": "ply"}


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    """One small rendered pose, its true calibration (JSON and YAML) and a tiny rig pose folder written by the
    simulator's rig writer (two pairs, 64x48 projectors, frames made without rendering)."""
    from sim_small import small_scene

    from procam import simulate as sim
    from procam.capture import pair_folder_name
    from procam.simulate import truth_calibration
    from procam.simulate.rig_capture import write_rig_capture

    root = tmp_path_factory.mktemp("world")
    pose = root / "pose"
    render_pose(pose, (15.0, 12.0, 0.0))
    calib = io.save_calibration(truth_calibration(small_scene()), root / "calib.json")
    io.save_calibration(truth_calibration(small_scene()), root / "calib.yml")
    rig = sim.rig_preset("two_projectors")
    cam = rig.cameras[0].name
    nc, npj = len(rig.cameras), len(rig.projectors)
    rendered = {pair_folder_name(cam, p.name, nc, npj): (cam, p.name, camera_view_of_patterns(64, 48, seed=i),
                                                          {"projector": {"size": [64, 48]}})
                for i, p in enumerate(rig.projectors)}
    rigs = []
    for k in range(3):
        write_rig_capture(root / f"rig{k + 1}", rig, rendered)
        rigs.append(root / f"rig{k + 1}")
    return {"root": root, "pose": pose, "calib": calib, "rigs": rigs, "projectors": list(rendered)}


def refused(args, *needles):
    """Run the CLI: exit 2, one line on stderr naming ``needles``, no traceback."""
    rc, out, err = run_cli(args)
    lines = [x for x in err.splitlines() if x.strip()]
    assert rc == 2 and len(lines) == 1 and "Traceback" not in err, (args, rc, out, err)
    for n in needles:
        assert n in err, (args, n, err)
    return err


# ------------------------------------------------------------------------------------------------
# one test per defect
def test_1_export_maps_with_force_never_overwrites_the_users_remap_tables(world, tmp_path):
    maps = tmp_path / "maps"
    mine = user_file(maps / "camera_undistort.npz", "npz")
    before = snapshot(maps)
    refused(["export", world["calib"], "--format", "maps", "-o", maps], "procam did not write")
    refused(["export", world["calib"], "--format", "maps", "--force", "-o", maps], "camera_undistort.npz",
            "procam did not write")
    assert snapshot(maps) == before and not (maps / "projector_predistort.npz").exists()
    # procam's own maps are known by their mark and rewritten
    mine.unlink()
    for _ in range(2):
        rc, _, err = run_cli(["export", world["calib"], "--format", "maps", "--force", "-o", maps])
        assert rc == 0, err
    assert _files.procam_wrote(maps / "camera_undistort.npz")


def test_2_a_rig_calibration_never_writes_over_its_input_rig_pose(world):
    rig1 = world["rigs"][0]
    man = _files.read_manifest(rig1)
    assert man["files"]["rig.json"] == "sidecar" and man["files"]["truth.json"] == "sidecar"
    before = snapshot(*world["rigs"])
    sub = rig1 / world["projectors"][0]
    for out, what in ((rig1 / "rig.json", "is rig.json of"), (rig1 / "truth.json", "is truth.json of"),
                      (sub / "patterns.json", "is patterns.json of"), (sub / "truth.json", "is truth.json of")):
        refused(["calibrate", *world["rigs"], *BOARD, "-o", out], what, "an input of this command")
    link = world["root"] / "out-link.json"  # a link to an input's file is that file
    link.symlink_to(rig1 / "rig.json")
    try:
        refused(["calibrate", *world["rigs"], *BOARD, "-o", link], "is rig.json of")
    finally:
        link.unlink()
    assert snapshot(*world["rigs"]) == before


def test_3_a_kamino410_export_never_overwrites_the_other_tools_result(world, tmp_path):
    theirs = user_file(tmp_path / "calibration_result.xml", "xml")
    yml = user_file(tmp_path / "calib.yml", "yml")
    before = snapshot(tmp_path)
    refused(["export", world["calib"], "--format", "kamino410", "-o", theirs], "procam did not write")
    refused(["export", world["calib"], "--format", "yaml", "-o", yml], "procam did not write")
    assert snapshot(tmp_path) == before
    # procam's own (its key procam_format) is rewritten
    for fmt, out in (("kamino410", tmp_path / "k.xml"), ("yaml", tmp_path / "p.yml"), ("yaml", tmp_path / "p.xml")):
        for _ in range(2):
            rc, _, err = run_cli(["export", world["calib"], "--format", fmt, "-o", out])
            assert rc == 0, err
        assert _files.procam_wrote(out) and io.load_calibration(out).camera is not None


def test_4_the_blender_export_never_overwrites_a_script_that_starts_with_procams_words(world, tmp_path):
    for first in ("# procam", "# procam-script sha256:", "# procam-script sha256:" + "0" * 64):
        script = tmp_path / "rig.py"
        script.write_text(first + "\nprint('mine')\n")
        before = script.read_bytes()
        refused(["export", world["calib"], "--format", "blender", "-o", tmp_path / "rig.json"], "rig.py",
                "procam did not write")
        assert script.read_bytes() == before and not (tmp_path / "rig.json").exists()
    script.unlink()
    for _ in range(2):
        rc, _, err = run_cli(["export", world["calib"], "--format", "blender", "-o", tmp_path / "rig.json"])
        assert rc == 0, err
    # a copy of procam's script the user edited is theirs
    text = script.read_text()
    script.write_text(text + "# my change\n")
    refused(["export", world["calib"], "--format", "blender", "-o", tmp_path / "rig.json"], "procam did not write")
    assert script.read_text() == text + "# my change\n"


def test_the_last_line_of_defence_refuses_a_users_file_whatever_the_caller_checked(tmp_path):
    from procam.errors import OutputError

    mine = user_file(tmp_path / "m.npz", "npz")
    before = mine.read_bytes()
    with pytest.raises(OutputError, match="procam did not write"):
        io.save_maps(mine, np.zeros((2, 2)), np.zeros((2, 2)))
    assert mine.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["m.npz"]


# ------------------------------------------------------------------------------------------------
# every writing command onto every file kind a user owns, and onto its inputs
def file_cases(w, d: Path) -> list:
    """(args, {path: kind of the user's file there}) for every file a command writes, ``d`` a fresh folder."""
    pose, calib = w["pose"], w["calib"]
    cal = ["calibrate", pose, *BOARD]
    exp = ["export", calib, "--format"]
    return [
        (cal + ["-o", d / "c.json"], {d / "c.json": "json"}),
        (cal + ["-o", d / "c.yml"], {d / "c.yml": "yml"}),
        (cal + ["-o", d / "c.json", "--yaml", d / "c.yml"], {d / "c.yml": "yml"}),
        (cal + ["-o", d / "c.json", "--png", d / "c.png"], {d / "c.png": "png"}),
        (cal + ["-o", d / "c.json", "--report", d / "c.html"], {d / "c.html": "html"}),
        (["evaluate", calib, pose, *BOARD, "-o", d / "e.json"], {d / "e.json": "json"}),
        (["reconstruct", calib, pose, "-o", d / "p.ply"], {d / "p.ply": "ply"}),
        (["reconstruct", calib, pose, "-o", d / "p2.ply", "--board", "10x6", "--residuals", d / "r.png"],
         {d / "r.png": "png"}),
        (["decode", pose, "-o", d / "m.npz"], {d / "m.npz": "npz"}),
        (["decode", pose, "--png", d / "d.png"], {d / "d.png": "png"}),
        (["correspond", pose, *BOARD, "-o", d / "k.json"], {d / "k.json": "json"}),
        (["correspond", pose, *BOARD, "-o", d / "k2.json", "--png", d / "k.png"], {d / "k.png": "png"}),
        (["report", calib, "-o", d / "r.html"], {d / "r.html": "html"}),
        (["check", pose, *BOARD, "--png", d / "o.png"], {d / "o.png": "png"}),
        (["check", pose, *BOARD, "--png", d / "o.jpg"], {d / "o.jpg": "jpg"}),
        (exp + ["opengl", "-o", d / "gl.json", "--near", "10", "--far", "1000"], {d / "gl.json": "json"}),
        (exp + ["unity", "-o", d / "u.json"], {d / "u.json": "json"}),
        (exp + ["unity", "-o", d / "u.json"], {d / "u_camera_undistort.npz": "npz"}),
        (exp + ["unity", "-o", d / "u.json"], {d / "u_camera_undistort_st.png": "png"}),
        (exp + ["blender", "-o", d / "b.json"], {d / "b.json": "json"}),
        (exp + ["blender", "-o", d / "b.json"], {d / "b.py": "py"}),
        (exp + ["kamino410", "-o", d / "k.xml"], {d / "k.xml": "xml"}),
        (exp + ["kamino410", "-o", d / "k.yml"], {d / "k.yml": "yml"}),
        (exp + ["yaml", "-o", d / "y.yml"], {d / "y.yml": "yml"}),
        (exp + ["yaml", "-o", d / "y.xml"], {d / "y.xml": "xml"}),
        (exp + ["projector-view", "--pose", pose, "-o", d / "v.png"], {d / "v.png": "png"}),
        (exp + ["projector-view", "--pose", pose, "-o", d / "v.png"], {d / "v_mask.png": "png"}),
    ]


def folder_cases(w, d: Path) -> list:
    """(args without --force, {path: kind}) for the commands that write into a folder."""
    rig1, calib = w["rigs"][0], w["calib"]
    p0 = w["projectors"][0]
    return [
        (["export", calib, "--format", "maps", "-o", d], {d / "camera_undistort.npz": "npz"}),
        (["export", calib, "--format", "maps", "-o", d, "--rectify"], {d / "projector_rectify.npz": "npz"}),
        (["patterns", "-p", "64x48", "-o", d], {d / "pattern_00.png": "png"}),
        (["patterns", "-p", "64x48", "-o", d], {d / "patterns.json": "json"}),
        (["simulate", d, "--seed", "1"], {d / "truth.json": "json"}),
        (["simulate", d, "--seed", "1"], {d / "17.png": "png"}),
        (["simulate", d, "--rig", "two_projectors"], {d / "rig.json": "json"}),
        (["simulate", d, "--rig", "two_projectors"], {d / "truth.json": "json"}),
        (["simulate", d, "--rig", "two_projectors"], {d / "left" / "00.png": "png"}),
        (["blend", rig1, "-o", d], {d / f"alpha_{p0}.png": "png"}),
        (["blend", rig1, "-o", d], {d / "blend.npz": "npz"}),
        (["study", "projector", "-o", d, "--grid", "0,15", "--trials", "2", "--slice-grid", "15", "--model-error",
          "none"], {d / "study_projector_none.json": "json"}),
        (["demo", d], {d / "calib.yml": "yml"}),
        (["demo", d], {d / "capture" / "truth.json": "json"}),
    ]


def input_cases(w, d: Path) -> list:
    """Commands whose output is one of their inputs, or a file an input folder needs (links followed)."""
    pose, calib, rigs = w["pose"], w["calib"], w["rigs"]
    root = w["root"]
    link = d / "link.json"
    link.symlink_to(calib)
    sub = rigs[0] / w["projectors"][0]
    return [
        ["calibrate", pose, *BOARD, "-o", pose / "truth.json"],
        ["calibrate", pose, *BOARD, "-o", pose / "patterns.json"],
        ["calibrate", pose, *BOARD, "-o", d / "c.json", "--png", pose / "00.png"],
        ["calibrate", *rigs, *BOARD, "-o", sub / "truth.json"],
        ["evaluate", calib, pose, *BOARD, "-o", calib],
        ["evaluate", calib, pose, *BOARD, "-o", link],
        ["decode", pose, "--png", pose / "05.png"],
        ["correspond", pose, *BOARD, "-o", pose / "capture.json"],
        ["reconstruct", calib, pose, "-o", d / "p.ply", "--board", "10x6", "--residuals", pose / "03.png"],
        ["check", pose, *BOARD, "--png", pose / "00.png"],
        ["export", calib, "--format", "opengl", "-o", calib, "--near", "10", "--far", "1000"],
        ["export", calib, "--format", "unity", "-o", link],
        ["export", root / "calib.yml", "--format", "yaml", "-o", root / "calib.yml"],
        ["export", calib, "--format", "projector-view", "--pose", pose, "-o", pose / "02.png"],
        ["blend", rigs[0], "-o", sub, "--force"],
        ["blend", rigs[0], "-o", rigs[0], "--force"],
        ["experiment", pose, rigs[1] / w["projectors"][1], rigs[2] / w["projectors"][0], *BOARD, "-o", pose, "--force"],
    ]


FORCE = {"export", "patterns", "simulate", "blend", "study", "demo"}


def test_every_writing_command_leaves_every_byte_of_the_users_files_and_its_inputs(world, tmp_path):
    inputs = snapshot(world["root"])
    n = 0
    for i, (args, files) in enumerate(file_cases(world, tmp_path / "f")):
        d = tmp_path / f"file{i}"
        args = [Path(str(a).replace(str(tmp_path / "f"), str(d))) if isinstance(a, Path) else a for a in args]
        for path, kind in files.items():
            user_file(Path(str(path).replace(str(tmp_path / "f"), str(d))), kind)
        before = snapshot(d)
        refused(args, "procam did not write")
        assert snapshot(d) == before, args
        n += 1
    for i, (args, files) in enumerate(folder_cases(world, tmp_path / "g")):
        for force in ((), ("--force",)):
            d = tmp_path / f"folder{i}{'f' if force else ''}"
            fix = [Path(str(a).replace(str(tmp_path / "g"), str(d))) if isinstance(a, Path) else a for a in args]
            for path, kind in files.items():
                user_file(Path(str(path).replace(str(tmp_path / "g"), str(d))), kind)
            before = snapshot(d)
            refused(fix + list(force), "procam did not write")
            assert snapshot(d) == before, fix + list(force)
            n += 1
    cap = user_file(tmp_path / "capture" / "00.png", "png").parent  # a capture never goes into a non-empty folder
    before = snapshot(cap)
    refused(["capture", cap, "--virtual", "--projector", "64x48"], "not empty")
    assert snapshot(cap) == before
    d = tmp_path / "inputs"
    d.mkdir()
    for args in input_cases(world, d):
        refused(args, "an input of this command")
        n += 1
    assert snapshot(world["root"]) == inputs
    assert n > 60 and not [p for p in tmp_path.rglob(".*tmp*")]


def test_a_rig_calibration_writes_over_its_own_yaml_and_json(monkeypatch, tmp_path):
    """The rig's FileStorage file carries procam's mark too (its writer takes it with the device keys)."""
    from rig_sim import fake_rig_folders

    _, folders = fake_rig_folders(monkeypatch, tmp_path)
    for _ in range(2):
        rc, out, err = run_cli(["calibrate", *folders, *BOARD, "-o", tmp_path / "rig.json", "--yaml",
                                tmp_path / "rig.yml"])
        assert rc == 0, (out, err)
    assert _files.procam_wrote(tmp_path / "rig.yml") and _files.procam_wrote(tmp_path / "rig.json")


def test_patterns_never_replace_the_description_of_another_sequence(tmp_path):
    """`procam patterns --force` into a simulated capture (or a copy of one) wrote its pattern_*.png beside the
    capture's frames and replaced the capture's patterns.json: the folder then decoded the patterns, not the
    capture.  A folder of its own earlier patterns still takes a shorter sequence (the longer one's frames go)."""
    from sim_small import small_capture

    from procam import patterns, simulate

    _, stack, truth, _ = small_capture()
    cap = tmp_path / "sim"
    simulate.write_capture(cap, stack, truth)
    before = snapshot(cap)
    code, _, err = run_cli(["patterns", "-o", cap, "--force", "-p", "1024x768"])
    assert code == 2 and f"-o {cap}: holds another sequence" in err and err.count("\n") == 1, err
    assert snapshot(cap) == before
    own = tmp_path / "pat"
    assert run_cli(["patterns", "-o", own, "-p", "1920x1080"])[0] == 0
    code, _, err = run_cli(["patterns", "-o", own, "-p", "1024x768"])
    assert code == 0, err
    names = sorted(p.name for p in own.glob("*.png"))
    assert len(names) == patterns.pattern_set(1024, 768).count and names[-1] == f"pattern_{len(names) - 1:02d}.png"


def test_a_cameras_frames_beside_a_copied_patterns_json_are_never_overwritten(tmp_path):
    """A user's capture: camera frames named pattern_NN.png (another tool's, unmarked) beside the patterns.json
    copied from `procam patterns`, no manifest.  `procam patterns` into it took the frames for an older procam's
    pattern images and wrote over all of them, even without --force."""
    import cv2

    from procam import patterns

    pat = tmp_path / "pat"
    assert run_cli(["patterns", "-o", pat, "-p", "320x200"])[0] == 0
    cap = tmp_path / "capture"
    cap.mkdir()
    (cap / "patterns.json").write_bytes((pat / "patterns.json").read_bytes())
    rng = np.random.default_rng(4)
    for k in range(patterns.pattern_set(320, 200).count):
        cv2.imwrite(str(cap / f"pattern_{k:02d}.png"), rng.integers(0, 255, (24, 32), dtype=np.uint8))
    before = snapshot(cap)
    for force in ([], ["--force"]):
        code, _, err = run_cli(["patterns", "-o", cap, "-p", "320x200", *force])
        assert code == 2 and "procam did not write" in err and err.count("\n") == 1, (force, err)
        assert snapshot(cap) == before
    assert run_cli(["patterns", "-o", pat, "-p", "320x200"])[0] == 0  # its own pattern images: rewritten


def _edit(path: Path) -> None:
    """A user's edit of a frame: one pixel changed, saved by another program (no procam mark)."""
    im = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    im[0, 0] ^= 255
    assert cv2.imwrite(str(path), im)


def test_a_frame_or_description_the_user_edited_is_never_rewritten_or_removed(tmp_path):
    """Round 5: a frame edited inside a `procam patterns` folder was rewritten by a rerun (the manifest listed it
    as procam's).  The manifest now records what procam wrote; an edited frame or patterns.json is refused (exit 2,
    one line naming it, every byte kept), with or without --force, whether it would be overwritten or removed as a
    stale frame of a longer sequence; moved away, the rest is procam's again."""
    from procam.io import formats

    pat = tmp_path / "pat"
    assert run_cli(["patterns", "-o", pat, "-p", "64x32"])[0] == 0
    man = _files.read_manifest(pat)
    assert man["digests"] and set(man["digests"]) == set(man["files"])
    assert all(_files.file_digest(pat / n) == d for n, d in man["digests"].items())
    assert run_cli(["patterns", "-o", pat, "-p", "64x32"])[0] == 0  # unedited: rewritten as before
    _edit(pat / "pattern_03.png")
    before = snapshot(pat)
    for args in (["-p", "64x32"], ["-p", "64x32", "--force"], ["-p", "16x8"]):
        code, _, err = run_cli(["patterns", "-o", pat, *args])
        assert code == 2 and "pattern_03.png" in err and "changed since procam wrote" in err, (args, err)
        assert err.count("\n") == 1 and snapshot(pat) == before
    # an edited frame the shorter sequence would delete as stale
    (pat / "pattern_03.png").rename(tmp_path / "mine.png")
    _edit(pat / "pattern_20.png")
    before = snapshot(pat)
    code, _, err = run_cli(["patterns", "-o", pat, "-p", "16x8"])
    assert code == 2 and "remove 1 frame(s)" in err and "pattern_20.png" in err and snapshot(pat) == before, err
    (pat / "pattern_20.png").rename(tmp_path / "mine20.png")
    assert run_cli(["patterns", "-o", pat, "-p", "64x32"])[0] == 0  # the moved frame is written again
    assert (pat / "pattern_03.png").is_file() and (pat / "pattern_20.png").is_file()
    # the description
    doc = json.loads((pat / "patterns.json").read_text())
    doc["note"] = "mine"
    (pat / "patterns.json").write_text(json.dumps(doc))
    before = snapshot(pat)
    code, _, err = run_cli(["patterns", "-o", pat, "-p", "64x32"])
    assert code == 2 and "patterns.json" in err and "changed since procam wrote" in err and snapshot(pat) == before
    assert not _files.procam_wrote(pat / "patterns.json")  # procam's JSON mark, but the digest decides
    assert json.loads((pat / "patterns.json").read_text())["format"].startswith(formats.JSON_PREFIX)
    from procam.errors import OutputError

    with pytest.raises(OutputError, match="changed since procam wrote it"):
        with _files.atomic_path(pat / "patterns.json"):
            pass


def test_an_interrupted_or_older_sequence_stays_procams_and_a_hostile_digest_list_is_ignored(tmp_path):
    """A frame's digest is dropped just before procam replaces it: a run killed half way leaves the frames it
    replaced procam's and the others protected.  A manifest without digests (an older procam's) reads as before;
    digests that are not strings, or name files the manifest does not list, are ignored."""
    from procam import patterns
    from procam.capture import write as _write

    pat = tmp_path / "pat"
    assert run_cli(["patterns", "-o", pat, "-p", "64x32"])[0] == 0
    ps = patterns.pattern_set(64, 32)
    with pytest.raises(RuntimeError):
        with _write.SequenceWriter(pat, ps, "pattern_") as w:
            w.add(0, np.full((32, 64), 7, np.uint8))  # another frame 0, then the run dies
            raise RuntimeError("killed")
    digests = _files.read_manifest(pat)["digests"]
    assert "pattern_00.png" not in digests and "pattern_01.png" in digests
    _edit(pat / "pattern_01.png")  # untouched by the killed run: still protected
    code, _, err = run_cli(["patterns", "-o", pat, "-p", "64x32"])
    assert code == 2 and "pattern_01.png" in err and "pattern_00" not in err, err
    (pat / "pattern_01.png").unlink()
    assert run_cli(["patterns", "-o", pat, "-p", "64x32"])[0] == 0
    # an older procam's manifest: no digests, its frames procam's by their listing
    doc = json.loads((pat / _files.MANIFEST).read_text())
    doc.pop("digests")
    (pat / _files.MANIFEST).write_text(json.dumps(doc))
    _edit(pat / "pattern_01.png")
    assert run_cli(["patterns", "-o", pat, "-p", "64x32"])[0] == 0
    # hostile digests
    doc = json.loads((pat / _files.MANIFEST).read_text())
    doc["digests"] = {"pattern_00.png": 5, "elsewhere.png": "blake2b-160:00", "../x": "y"}
    (pat / _files.MANIFEST).write_text(json.dumps(doc))
    assert _files.read_manifest(pat)["digests"] == {}
    assert run_cli(["patterns", "-o", pat, "-p", "64x32"])[0] == 0
    doc["digests"] = ["not", "a", "mapping"]
    (pat / _files.MANIFEST).write_text(json.dumps(doc))
    assert _files.read_manifest(pat)["digests"] == {} and _files.procam_wrote(pat / "pattern_00.png")
    # a listed name of a role procam does not know, with its digest: written over without an internal error
    doc = json.loads((pat / _files.MANIFEST).read_text())
    doc["files"]["maps.npz"] = "bogus"
    (pat / "maps.npz").write_bytes(b"")
    doc["digests"] = {"maps.npz": _files.file_digest(pat / "maps.npz")}
    (pat / _files.MANIFEST).write_text(json.dumps(doc))
    _files.write_npz(pat / "maps.npz", a=np.zeros(3))
    assert _files.read_manifest(pat)["digests"]["maps.npz"] == _files.file_digest(pat / "maps.npz")
    # a camera's frame with its digest forged in: still never procam's to replace
    doc = json.loads((pat / _files.MANIFEST).read_text())
    doc["files"]["pattern_02.png"] = "captured"
    doc["digests"]["pattern_02.png"] = _files.file_digest(pat / "pattern_02.png")
    (pat / _files.MANIFEST).write_text(json.dumps(doc))
    assert not _files.procam_wrote(pat / "pattern_02.png")


def test_every_file_procam_writes_into_a_manifest_folder_is_protected_from_overwriting_an_edit(tmp_path,
                                                                                                monkeypatch):
    """Round 6: a rig's top-level rig.json and truth.json (written one by one, not by the sequence writer) had no
    digest, so an edit of them was written over.  Any file written into a folder with a manifest now gets its
    digest once written; procam writing it again replaces the digest; one that cannot be read to check is
    refused, not taken for procam's."""
    from procam.errors import OutputError

    pat = tmp_path / "pat"
    assert run_cli(["patterns", "-o", pat, "-p", "64x32"])[0] == 0
    _files.write_text(pat / "rig.json", "{}", role="sidecar")
    _files.write_text(pat / "notes.txt", "procam's")
    man = _files.read_manifest(pat)
    assert man["digests"]["rig.json"] == _files.file_digest(pat / "rig.json")
    assert man["digests"]["notes.txt"] == _files.file_digest(pat / "notes.txt")
    _files.write_text(pat / "rig.json", '{"a": 1}', role="sidecar")  # procam again: the new digest
    assert _files.read_manifest(pat)["digests"]["rig.json"] == _files.file_digest(pat / "rig.json")
    (pat / "rig.json").write_text('{"a": 2}')  # the user's edit
    for name in ("rig.json", "notes.txt"):
        if name == "notes.txt":
            (pat / name).write_text("mine")
        before = (pat / name).read_bytes()
        with pytest.raises(OutputError, match="changed since procam wrote it"):
            _files.write_text(pat / name, "{}", role="sidecar")
        assert (pat / name).read_bytes() == before
    # unreadable: refused, and a stale frame that cannot be read is not removed
    real = _files.file_digest

    def unreadable(path):
        if Path(path).name == "pattern_20.png":
            raise PermissionError(13, "Permission denied", str(path))
        return real(path)

    monkeypatch.setattr(_files, "file_digest", unreadable)
    assert _files.changed_since_written(pat / "pattern_20.png") and not _files.procam_wrote(pat / "pattern_20.png")
    before = snapshot(pat)
    code, _, err = run_cli(["patterns", "-o", pat, "-p", "16x8"])
    assert code == 2 and "pattern_20.png" in err and snapshot(pat) == before, err
