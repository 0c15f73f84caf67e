"""Tests of the simulator's scenes: backgrounds fixed in the room (occlusion, shadows), the presets of real rigs,
the dense fast path (true_projector_maps) and rigs of several devices."""

from __future__ import annotations

import json

import numpy as np
import pytest

from procam import simulate as sim

NEW_PRESETS = ("lensshift", "hard", "vertical", "ceiling")


def _small(scene: sim.Scene, supersample: int = 2) -> sim.Scene:
    """A scene at a quarter of its pixels (same angles of view), the board placed again: cheap to render."""
    return sim.with_board_pose(scene.scaled(0.25).replace(supersample=supersample), sim.RECOMMENDED_POSE)


def _render_and_decode(scene, seed=1):
    """Render ``scene``, decode it plainly; returns (true maps rounded like a decode, where the decode is within one
    projector pixel of them in both coordinates, the stack, the truth)."""
    from procam import decode, patterns

    stack, t = sim.render(scene, seed=seed)
    ps = patterns.pattern_set(*scene.proj_size, "opencv")
    r = decode.decode(stack, ps, method="simple", contrast_threshold=0.0, shadow_threshold=1.0)
    m = sim.true_projector_maps(scene, rounded=True)
    return m, (np.abs(r.col - m.col) <= 1) & (np.abs(r.row - m.row) <= 1), stack, t


def _rays(scene, rc):
    """Camera rays (N, 3), z = 1, through the pixel centres at (row, col) ``rc`` (N, 2)."""
    und = sim.undistort(scene, np.column_stack([rc[:, 1], rc[:, 0]]).astype(float))
    K = scene.K_cam
    return np.column_stack([(und[:, 0] - K[0, 2]) / K[0, 0], (und[:, 1] - K[1, 2]) / K[1, 1], np.ones(len(rc))])


def _wall_box_scene(**kw):
    """The paper's rig before a wall at 1200 mm with a box between the board and the wall, lit by the projector."""
    room = sim.Background((sim.Plane((0.0, 0.0, 1200.0), (0.0, 0.0, 1.0)),
                           sim.Box.at((150.0, -180.0, 950.0), (100.0, 80.0, 60.0), (0.0, 20.0, 0.0), 0.8)))
    return sim.with_board_pose(sim.Scene(background=room, supersample=1, **kw), sim.RECOMMENDED_POSE)


# ---------------------------------------------------------------------------------------------
# backgrounds
# ---------------------------------------------------------------------------------------------

def test_the_default_wall_moves_with_the_board_and_a_background_stays_in_the_room():
    s = sim.preset("paper")
    moved = sim.with_board_pose(s, (0.0, 20.0, 0.0), distance=700.0)
    assert moved.surfaces().surfaces[0].point[2] == 1000.0 != s.surfaces().surfaces[0].point[2]
    room = s.replace(background=sim.Background.wall(1000.0))
    a = sim.true_projector_maps(room.replace(supersample=1), step=8)
    b = sim.true_projector_maps(sim.with_board_pose(room, (0.0, 20.0, 0.0)).replace(supersample=1), step=8)
    both = (a.surface == 1) & (b.surface == 1) & a.lit & b.lit
    assert both.sum() > 200
    np.testing.assert_array_equal(a.col[both], b.col[both])  # the same wall point lit by the same projector pixel
    t = sim.truth(room)
    assert t["background"]["fixed_in_room"] and t["wall"] is None
    assert not sim.truth(s)["background"]["fixed_in_room"] and sim.truth(s)["wall"]["offset"] == 300.0


def test_a_box_hides_the_wall_behind_it_and_casts_a_shadow_on_it():
    s = _wall_box_scene()
    m = sim.true_projector_maps(s)
    box = s.background.surfaces[1]
    # the camera sees the box at its centre's pixel, not the wall behind it (nearest hit)
    u, v = np.rint(sim.project(s.K_cam, box.center[None])[0]).astype(int)
    assert m.surface[v, u] == 2 and m.lit[v, u]
    # a wall point is in shadow exactly where the box or the board lies between it and the projector
    wall = m.surface == 1
    rays = _rays(s, np.argwhere(wall))
    Q = rays * (1200.0 / rays[:, 2:3])
    L = s.proj_center_cam - Q
    by_box = box.blocks(Q, L)
    nb, tb = s.R_board[:, 2], s.t_board
    u = ((tb - Q) @ nb) / (L @ nb)
    B = (Q + u[:, None] * L - tb) @ s.R_board
    x0, x1, y0, y1 = sim.board_extent(s)
    by_board = (u > 0) & (u < 1) & (B[:, 0] >= x0) & (B[:, 0] <= x1) & (B[:, 1] >= y0) & (B[:, 1] <= y1)
    assert by_box.sum() > 500 and by_board.sum() > 1000  # the camera sees both shadows
    np.testing.assert_array_equal(m.shadow[wall], by_box | by_board)
    assert not m.lit[wall][by_box].any() and np.isnan(m.col[wall][by_box]).all()
    # everything the camera sees lit has a projector coordinate
    assert np.isfinite(m.col[m.lit]).all() and np.isnan(m.col[~m.lit]).all()
    # the projector coordinates on the box are those of the points of the box the camera sees
    on = np.argwhere(m.lit & (m.surface == 2))[::50]
    rays = _rays(s, on)
    X = rays * box.hit(np.zeros(3), rays)[:, None]
    proj = sim.project_points(s, X @ s.R.T + s.T, "projector")
    np.testing.assert_allclose(np.column_stack([m.col[on[:, 0], on[:, 1]], m.row[on[:, 0], on[:, 1]]]), proj,
                               atol=1e-6)


def test_a_solid_between_projector_and_board_shadows_the_board():
    """Shadows on the board: its pixels behind a ball (from the projector) are unlit, their corners are not visible,
    and the placement refuses such a pose."""
    s = sim.preset("paper")
    Cp, c = s.proj_center_cam, s.t_board
    ball = sim.Sphere(Cp + 0.5 * (c - Cp), 15.0)
    sh = s.replace(background=sim.Background((sim.Plane((0, 0, 1000.0), (0, 0, 1.0)), ball)), supersample=1)
    m = sim.true_projector_maps(sh, step=2)
    on_board_shadow = m.board & m.shadow
    assert on_board_shadow.sum() > 100
    assert not (m.lit_board & on_board_shadow).any()
    assert sim.fit_margin(sh) == -1e9
    c = sim.corner_truth(sh)
    assert c["shadowed"].any() and np.array_equal(c["visible"], ~(c["hidden"] | c["shadowed"]))
    # the fast corner path has no projector coordinate in the shadow (no code to decode there), nor a camera
    # corner where the ball hides the board from the camera
    _, cam, proj = sim.correspondences(sh, 0.0, 0.0)
    np.testing.assert_array_equal(np.isnan(proj).any(axis=1), c["hidden"] | c["shadowed"])
    np.testing.assert_array_equal(np.isnan(cam).any(axis=1), c["hidden"])
    assert sim.fit_margin(sim.with_board_pose(sh, sim.RECOMMENDED_POSE)) > 0  # another position is found


def test_a_room_corner_switches_walls_at_its_edge():
    """Two walls meeting in a vertical edge: along a camera row the nearest wall switches where the edge is seen."""
    edge = np.array([100.0, 0.0, 1200.0])
    room = sim.Background((sim.Plane(edge, (0.5, 0.0, -1.0)), sim.Plane(edge, (-0.5, 0.0, -1.0))))
    s = sim.Scene(background=room, cam_distortion="none", cam_dist_coeffs=(), supersample=1,
                  t_board=(0.0, 0.0, -5000.0))  # the board out of sight
    m = sim.true_projector_maps(s, step=1)
    row = m.surface[400]
    u_edge = sim.project(s.K_cam, edge[None])[0, 0]
    assert set(row[: int(u_edge) - 1]) == {1} and set(row[int(u_edge) + 2:]) == {2}


def test_background_refuses_devices_on_both_sides_of_a_wall():
    with pytest.raises(ValueError, match="one side"):
        sim.Scene(background=sim.Background.wall(50.0))  # the projector stands at z = 105 mm, behind it
    with pytest.raises(ValueError, match="contains the camera"):
        sim.Scene(background=sim.Background((sim.Sphere((0, 0, 0), 10.0),)))
    with pytest.raises(ValueError):
        sim.Background(())


# ---------------------------------------------------------------------------------------------
# the dense fast path
# ---------------------------------------------------------------------------------------------

def test_true_projector_maps_subsample_and_round_like_a_decode():
    s = _small(sim.preset("hard"))
    full = sim.true_projector_maps(s)
    col, row, lit = full  # unpacks as before
    assert col is full.col and lit is full.lit_board and full.step == 1 and not full.rounded
    sub = sim.true_projector_maps(s, step=3)
    np.testing.assert_array_equal(sub.col, full.col[::3, ::3])
    np.testing.assert_array_equal(sub.surface, full.surface[::3, ::3])
    np.testing.assert_array_equal(sub.lit_board, full.lit_board[::3, ::3])
    np.testing.assert_array_equal(sub.y, np.arange(0, s.cam_size[1], 3))
    r = sim.true_projector_maps(s, rounded=True)
    ok = np.isfinite(full.col)
    np.testing.assert_array_equal(r.col[ok], np.clip(np.floor(full.col[ok] + 0.5), 0, s.proj_size[0] - 1))
    assert r.rounded and np.array_equal(np.isfinite(r.col), ok)
    assert set(np.unique(full.surface)) == {0, 1, 2, 3, 4}  # the board, two walls, the box and the ball
    with pytest.raises(ValueError):
        sim.true_projector_maps(s, step=0)


# ---------------------------------------------------------------------------------------------
# presets
# ---------------------------------------------------------------------------------------------

def test_new_presets_have_their_documented_numbers():
    ls = sim.preset("lensshift")
    np.testing.assert_allclose(ls.K_proj[:2, 2], [960 + 21, 1.08 * 1080])
    assert ls.proj_dist_coeffs == (-0.10, 0.015, 0.0, 0.0, 0.0) and ls.fixed_background
    hard = sim.preset("hard")
    assert len(hard.background.surfaces) == 4 and not hard.proj_lens.describable(hard.K_proj)
    np.testing.assert_allclose(hard.K_proj[:2, 2], [930, 1134])
    v = sim.preset("vertical")
    np.testing.assert_allclose(v.proj_center_cam, [0, 600, 0], atol=1e-9)  # 0.6 m below the camera (y down)
    c = sim.preset("ceiling")
    assert c.R[1] @ [0, 1, 0] < -0.9  # the projector's y axis points up in the room: upside down
    assert c.proj_center_cam[1] == pytest.approx(-350)  # above the camera
    assert abs(abs(sim.truth(c)["pose"]["projector"]["angles_deg"][2]) - 180) < 10
    for scene in (ls, hard, v, c):
        np.testing.assert_allclose(scene.K_cam, sim.preset("paper").K_cam)


@pytest.mark.parametrize("name", NEW_PRESETS)
def test_every_preset_sees_the_board_whole_from_both_devices(name):
    s = sim.preset(name)
    t = sim.truth(s)
    assert sim.fit_margin(s) > 5 and t["fit_margin_px"] > 5
    np.testing.assert_allclose(t["pose"]["camera"]["angles_deg"], sim.RECOMMENDED_POSE, atol=1e-9)
    assert all(t["corners"]["visible"])
    cam, proj = np.array(t["corners"]["camera_distorted"]), np.array(t["corners"]["projector"])
    assert cam.min() > 0 and cam[:, 0].max() < 1279 and cam[:, 1].max() < 799
    assert proj.min() > 0 and proj[:, 0].max() < 1919 and proj[:, 1].max() < 1079
    json.dumps(t)


@pytest.mark.parametrize("name", NEW_PRESETS)
def test_every_preset_renders_and_decodes_plausibly(name):
    """A small render of each preset decodes to the true projector pixels on the board and on the lit background."""
    s = _small(sim.preset(name))
    assert sim.fit_margin(s) > 0
    m, near, stack, t = _render_and_decode(s)
    assert m.lit_board.sum() > 10_000
    assert near[m.lit_board].mean() > 0.98
    background = m.lit & (m.surface > 0)
    assert background.sum() > 1000 and near[background].mean() > 0.95
    white, black = stack[t["render"]["white"]].astype(int), stack[t["render"]["black"]].astype(int)
    assert np.median((white - black)[m.lit_board]) > 30


# ---------------------------------------------------------------------------------------------
# rigs
# ---------------------------------------------------------------------------------------------

def test_a_rig_of_one_pair_gives_back_its_scene():
    s = sim.preset("lensshift")
    cam = sim.Device("c", "camera", s.cam_size, s.K_cam, s.cam_lens)
    proj = sim.Device("p", "projector", s.proj_size, s.K_proj, s.proj_lens, s.R, s.T)
    rig = sim.Rig((cam,), (proj,), s)
    pair = rig.scene()
    for k in ("K_cam", "K_proj", "R", "T", "R_board", "t_board"):
        np.testing.assert_allclose(getattr(pair, k), getattr(s, k), atol=1e-12)
    a, b = sim.corner_truth(pair), sim.corner_truth(s)
    for k in ("camera_distorted", "projector"):
        np.testing.assert_allclose(a[k], b[k], atol=1e-9)
    np.testing.assert_allclose(sim.truth_calibration(pair).T, s.T)


@pytest.mark.parametrize("name", sim.RIG_PRESETS)
def test_rig_truth_holds_every_device_and_every_relative_pose(name):
    rig = sim.rig_preset(name)
    t = json.loads(json.dumps(rig.truth()))
    names = [d.name for d in rig.devices]
    assert set(t["devices"]) == set(names) and t["reference"] == rig.cameras[0].name
    assert len(t["relative"]) == len(names) * (len(names) - 1)
    for a in names:
        for b in names:
            for c in names:
                if len({a, b, c}) == 3:  # poses compose: a -> b -> c is a -> c
                    Rab, Tab = rig.relative_pose(a, b)
                    Rbc, Tbc = rig.relative_pose(b, c)
                    Rac, Tac = rig.relative_pose(a, c)
                    np.testing.assert_allclose(Rbc @ Rab, Rac, atol=1e-12)
                    np.testing.assert_allclose(Rbc @ Tab + Tbc, Tac, atol=1e-9)
        for b in names:
            if a != b:
                np.testing.assert_allclose(t["relative"][f"{a}->{b}"]["baseline"],
                                           np.linalg.norm(rig.device(a).center - rig.device(b).center), atol=1e-9)
    # every pair sees the board whole, and it is one board: the same 3-D corners in the reference frame
    assert rig.fit_margin() > 5
    ref = rig.cameras[0]
    corners = []
    for cam, proj in rig.pairs():
        s = rig.scene(cam, proj)
        c = sim.corner_truth(s)
        assert sim.fit_margin(s) > 5 and c["visible"].all()
        d = rig.device(cam)
        Xc = c["board"] @ s.R_board.T + s.t_board
        corners.append((Xc - d.T) @ d.R)   # back to the reference frame
        np.testing.assert_allclose(t["pose"][cam]["t"], s.t_board, atol=1e-9)
        np.testing.assert_allclose(t["pose"][proj]["t"], s.t_board_proj, atol=1e-9)
    for X in corners[1:]:
        np.testing.assert_allclose(X, corners[0], atol=1e-9)
    assert ref.name == t["reference"]


def test_two_projectors_overlap_on_the_wall_and_each_renders_in_the_camera():
    rig = sim.rig_preset("two_projectors")
    assert np.linalg.norm(rig.device("left").center - rig.device("right").center) == pytest.approx(500.0)
    maps = {p: sim.true_projector_maps(rig.scene("cam", p).replace(supersample=1), step=4) for p in ("left", "right")}
    lit = {p: m.lit & (m.surface == 1) for p, m in maps.items()}
    both = lit["left"] & lit["right"]
    for p in lit:
        assert 0.25 < both.sum() / lit[p].sum() < 0.75  # overlapping, not the same image
    m, near, _, _ = _render_and_decode(_small(rig.scene("cam", "right")))
    assert near[m.lit_board].mean() > 0.98


def test_rig_of_two_cameras_renders_the_projector_in_the_second_camera():
    rig = sim.rig_preset("two_cameras")
    s = _small(rig.scene("right", "proj"))
    assert s.cam_distortion == "opencv" and sim.fit_margin(s) > 0
    m, near, _, _ = _render_and_decode(s)
    assert near[m.lit_board].mean() > 0.98


def test_rig_refuses_what_cannot_be():
    paper = sim.preset("paper")
    cam = sim.Device("c", "camera", paper.cam_size, paper.K_cam)
    proj = sim.Device("p", "projector", paper.proj_size, paper.K_proj, R=paper.R, T=paper.T)
    with pytest.raises(ValueError, match="unique"):
        sim.Rig((cam,), (sim.Device("c", "projector", paper.proj_size, paper.K_proj),), paper)
    with pytest.raises(ValueError, match="reference"):
        sim.Rig((sim.Device("c", "camera", paper.cam_size, paper.K_cam, T=(1.0, 0, 0)),), (proj,), paper)
    with pytest.raises(ValueError, match="one side"):
        far = sim.Device("q", "projector", paper.proj_size, paper.K_proj, T=(0, 0, -2000.0))  # behind the wall
        sim.Rig((cam,), (proj, far), paper.replace(background=sim.Background.wall(1500.0)))
    rig = sim.Rig((cam,), (proj,), paper)
    assert rig.template.fixed_background  # the default wall, fixed where it stood
    with pytest.raises(KeyError, match="no device"):
        rig.scene(projector="nope")
    with pytest.raises(ValueError, match="camera and a projector"):
        rig.scene(camera="p", projector="p")
    with pytest.raises(ValueError):
        sim.rig_preset("nope")
