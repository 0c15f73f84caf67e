"""``procam simulate --rig`` and ``procam calibrate`` of rig pose folders (issue 27): a fast run on the corner fast
path (the folders' decoding replaced by the simulator's views) and a rendered end to end run (slow)."""

from __future__ import annotations

import json
import numpy as np
import pytest

from conftest import run_cli
from rig_sim import ANGLES, fake_rig_folders as _fake_rig_folders


def test_calibrate_rig_folders_writes_one_file_of_every_device(monkeypatch, tmp_path):
    from procam.io import load_calibration

    rig, folders = _fake_rig_folders(monkeypatch, tmp_path)
    out = tmp_path / "rig.json"
    code, stdout, _ = run_cli(["calibrate", *folders, "--board", "10x6", "--square", "24", "-o", out,
                               "--yaml", tmp_path / "rig.yml", "--png", tmp_path / "rig.png"])
    assert code == 0, stdout
    assert "left->right" in stdout and "rig verification" in stdout
    doc = json.loads(out.read_text())
    assert doc["format"] == "procam-rig-calibration" and set(doc["projectors"]) == {"left", "right"}
    assert doc["poses"] == ["pose1", "pose2", "pose3"]  # relative to the file's folder
    _, T = rig.relative_pose("cam", "right")
    assert np.linalg.norm(load_calibration(out, pair="right").T - T) < 0.5
    assert (tmp_path / "rig.yml").is_file() and (tmp_path / "rig.png").stat().st_size > 10000


def test_calibrate_refuses_a_mix_of_rig_and_ordinary_poses(monkeypatch, tmp_path):
    _, folders = _fake_rig_folders(monkeypatch, tmp_path, n_poses=2)
    plain = tmp_path / "plain"
    plain.mkdir()
    (plain / "00.png").write_bytes(b"")
    code, _, err = run_cli(["calibrate", folders[0], plain, "--board", "10x6", "--square", "24", "-o",
                            tmp_path / "c.json"])
    assert code == 2 and "not a rig pose folder" in err and not (tmp_path / "c.json").exists()


@pytest.mark.slow
def test_rendered_rig_end_to_end(tmp_path):
    """simulate --rig two_projectors at three poses (rendered, 1280x800), calibrate: within 3 std of the truth,
    the projector-to-projector translation within 0.5 % of the baseline."""
    from procam import models
    from procam import simulate as sim
    from procam.io.rig import load_rig_document

    folders = []
    for j, a in enumerate(ANGLES):
        f = tmp_path / f"pose{j + 1}"
        code, stdout, _ = run_cli(["simulate", f, "--rig", "two_projectors", "--pose", ",".join(map(str, a)),
                                   "--seed", 10 * j])
        assert code == 0, stdout
        folders.append(f)
    out = tmp_path / "rig.json"
    code, stdout, _ = run_cli(["calibrate", *folders, "--board", "10x6", "--square", "24", "-o", out])
    assert code == 0, stdout
    doc = load_rig_document(out)
    rig = sim.rig_preset("two_projectors")
    for name, d in {**doc["cameras"], **doc["projectors"]}.items():
        K = np.array(d["K"])
        Kt = rig.device(name).K
        for key, i, j in (("f", 0, 0), ("fy", 1, 1), ("u0", 0, 2), ("v0", 1, 2)):
            assert abs(K[i, j] - Kt[i, j]) < 3 * d["std"][key], (name, key)
    for key, r in doc["relative"].items():
        a, b = key.split("->")
        R, T = rig.relative_pose(a, b)
        assert np.all(np.abs(np.array(r["T"]) - T) < 3 * np.array(r["std"]["T"])), key
        assert np.all(np.abs(np.array(r["angles_deg"]) - models.euler_deg(R)) < 3 * np.array(r["std"]["angles_deg"]))
    _, T = rig.relative_pose("left", "right")
    assert np.linalg.norm(np.array(doc["relative"]["left->right"]["T"]) - T) <= 0.005 * np.linalg.norm(T)
    # the blend masks of the first pose's two projectors
    code, stdout, _ = run_cli(["blend", folders[0], "-o", tmp_path / "blend"])
    assert code == 0, stdout
    from procam.io.images import read_image

    a = read_image(tmp_path / "blend" / "alpha_left.png")
    assert a.dtype == np.uint16 and a.shape == (1080, 1920) and a.min() < 1000 and a.max() == 65535


@pytest.mark.slow    # fast sibling: test_rig_cli's calibrate test
def test_export_covers_every_device_of_a_rig(monkeypatch, tmp_path):
    _, folders = _fake_rig_folders(monkeypatch, tmp_path)
    out = tmp_path / "rig.json"
    assert run_cli(["calibrate", *folders, "--board", "10x6", "--square", "24", "-o", out])[0] == 0
    code, _, err = run_cli(["export", out, "--format", "opengl", "--near", "100", "--far", "5000", "-o",
                            tmp_path / "x.json"])
    assert code == 2 and "--pair" in err
    worlds = {}
    for p in ("left", "right"):
        code, stdout, _ = run_cli(["export", out, "--pair", p, "--format", "opengl", "--near", "100", "--far", "5000",
                                   "-o", tmp_path / f"{p}.json"])
        assert code == 0, stdout
        worlds[p] = json.loads((tmp_path / f"{p}.json").read_text())
    # both in the reference camera's world: the same camera, different projectors
    assert worlds["left"]["camera"] == worlds["right"]["camera"]
    assert worlds["left"]["projector"] != worlds["right"]["projector"]
