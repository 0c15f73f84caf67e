"""The simulation study: METHOD §12's noise-free tables, |Δf| against the CRLB, parallel backends, CLI."""

import builtins
import csv
import sys

import numpy as np
import pytest

from procam.errors import ProcamError
from procam.paper.study import StudyConfig, StudyResult, cell_scene, parse_grid, run_cell, run_study, study_cells


def test_parse_grid():
    assert parse_grid("-45:45:5").size == 19
    assert parse_grid("-45:45:5")[[0, -1]].tolist() == [-45.0, 45.0]
    assert parse_grid("0:1:0.25").tolist() == [0, 0.25, 0.5, 0.75, 1.0]
    assert parse_grid("10, -3.5").tolist() == [-3.5, 10.0]
    for bad in ("", "1:2", "5:-5:1", "0:10:0", "a,b", "-90:0:10", "0:1e300:1e300", "1e300,0"):
        with pytest.raises(ProcamError):
            parse_grid(bad)


def test_cells_include_the_papers_slices_once():
    cam = StudyConfig("camera", psi=[-10, 0, 10], nu=[-10, 0, 10])
    cells = study_cells(cam)
    keys = [(p, n) for p, n, _, _ in cells]
    assert len(keys) == len(set(keys)) == 9  # both camera slices lie on this grid
    assert dict(((p, n), s) for p, n, _, s in cells)[(10.0, 10.0)] == "nu=10;psi=10"
    proj = study_cells(StudyConfig("projector", psi=[-10, 0, 10], nu=[-10, 0, 10]))
    extra = [(p, n) for p, n, g, _ in proj if not g]
    assert sorted(extra) == sorted([(a, s) for a in (-10.0, 0.0, 10.0) for s in (-3.5, 3.5)])
    assert len(study_cells(StudyConfig("camera", psi=[0], nu=[0], slices=False))) == 1


def test_cell_geometry_is_the_papers():
    """Board centred on the device axis at D = 500 mm, rotated about its centre, phi = 0 (METHOD §12)."""
    from procam.models import euler_to_matrix

    for device in ("camera", "projector"):
        cfg = StudyConfig(device)
        s = cell_scene(cfg, 20.0, -30.0)
        R, t = (s.R_board, s.t_board) if device == "camera" else (s.R_board_proj, s.t_board_proj)
        np.testing.assert_allclose(R, euler_to_matrix(*np.radians([20.0, -30.0, 0.0])), atol=1e-12)
        np.testing.assert_allclose(t, [0, 0, 500.0], atol=1e-9)
    assert cell_scene(StudyConfig("camera"), 0, 0).cam_distortion == "none"  # §12: no lens distortion
    # model error "none": the projector truth satisfies alpha_p = 1, the method's assumption
    Kp = cell_scene(StudyConfig("projector", model_error="none"), 0, 10).K_proj
    assert Kp[1, 1] == Kp[0, 0]


# METHOD §12 "Expected outcome": noise-free |Δf| with the paper's model errors, D = 500 mm
CAMERA_NF = {(-10, 10): 28.4, (-2, 10): 89.7, (10, 10): 1.1, (45, 10): 6.7, (10, -45): 28.8, (10, 20): 10.2}
PROJ_NF = {(10, -10): 228, (10, 5): 634, (10, 45): 60, (-45, 3.5): 488, (-5, 3.5): 1054}


@pytest.mark.parametrize("device,cells", [("camera", CAMERA_NF), ("projector", PROJ_NF)])
def test_noise_free_model_error_reproduces_method_tables(device, cells):
    cfg = StudyConfig(device, trials=0, model_error="paper")
    for (psi, nu), ref in cells.items():
        row = run_cell(cfg, psi, nu)
        assert row["abs_df_noise_free"] == pytest.approx(ref, rel=0.01, abs=0.1), (psi, nu)
        assert row["n_ok"] == 0 and np.isnan(row["median_abs_df"])


def test_noise_free_without_model_error_is_exact():
    for device, cell in (("camera", (20, -30)), ("projector", (10, 20))):
        row = run_cell(StudyConfig(device, trials=0, model_error="none"), *cell)
        assert row["abs_df_noise_free"] < 1e-3


def _check_tracks_bound(device, cell, trials):
    cfg = StudyConfig(device, trials=trials, model_error="none", seed=3)
    row = run_cell(cfg, *cell)
    assert row["n_ok"] == trials
    assert row["bound_f"] == pytest.approx(cfg.sigma * row["bound_f_per_px"])
    # the sample std of n trials is within ~ +-2.5/sqrt(2n) of sigma; median |x| of N(0, s) is 0.674 s
    tol = 2.5 / np.sqrt(2 * trials)
    assert 1 - tol < row["ratio_std"] < 1 + tol
    assert 0.674 * (1 - 2 * tol) < row["ratio_median"] < 0.674 * (1 + 2 * tol)
    assert abs(row["mean_df"]) < 3 * row["bound_f"] / np.sqrt(trials) + 0.5


@pytest.mark.parametrize("device,cell", [pytest.param("camera", (20, 20), marks=pytest.mark.slow), ("projector", (-30, -20))])
def test_noisy_spread_tracks_the_bound_without_model_error(device, cell):
    _check_tracks_bound(device, cell, 40)


@pytest.mark.slow
@pytest.mark.parametrize("device,cell", [("camera", (-10, 30)), ("camera", (5, 10)), ("projector", (10, 10)),
                                         ("projector", (0, 5))])
def test_noisy_spread_tracks_the_bound_more_cells(device, cell):
    _check_tracks_bound(device, cell, 150)


def test_run_is_reproducible_and_order_independent():
    cfg = StudyConfig("projector", psi=[10.0], nu=[10.0, 20.0], trials=3, slices=False)
    a = run_study(cfg)
    b = run_study(cfg, cells=list(reversed(study_cells(cfg))))
    key = lambda r: (r["psi"], r["nu"])  # noqa: E731
    for ra, rb in zip(sorted(a.rows, key=key), sorted(b.rows, key=key)):
        assert ra["f_median"] == rb["f_median"]


def _strip(rows):
    """Rows without their timing, NaN replaced by a marker so that NaN == NaN."""
    return [{k: ("nan" if isinstance(v, float) and v != v else v) for k, v in r.items() if k != "seconds"}
            for r in rows]


@pytest.mark.slow
def test_joblib_processes_give_the_serial_result():
    pytest.importorskip("joblib")
    cfg = StudyConfig("camera", psi=[-10.0, 10.0], nu=[5.0, 20.0], trials=2, slices=False)
    seen = []
    serial = run_study(cfg)
    par = run_study(cfg, n_jobs=2, chunk_size=1, progress=lambda d, t: seen.append((d, t)))
    assert _strip(par.rows) == _strip(serial.rows)
    assert seen[-1] == (4, 4) and len(seen) == 4
    assert par.run["backend"] == "loky"


def test_serial_study_runs_without_joblib(monkeypatch):
    real_import = builtins.__import__

    def no_joblib(name, *args, **kwargs):
        if name == "joblib" or name.startswith("joblib."):
            raise ImportError("no joblib")
        return real_import(name, *args, **kwargs)

    monkeypatch.delitem(sys.modules, "joblib", raising=False)
    monkeypatch.setattr(builtins, "__import__", no_joblib)
    cfg = StudyConfig("projector", psi=[10.0], nu=[20.0], trials=1, slices=False)
    assert run_study(cfg).rows[0]["n_ok"] == 1
    with pytest.raises(ProcamError, match="joblib"):
        run_study(cfg, n_jobs=2)


def test_dask_backend_on_a_local_cluster():
    pytest.importorskip("joblib")
    distributed = pytest.importorskip("dask.distributed")
    cfg = StudyConfig("projector", psi=[10.0], nu=[10.0, 30.0], trials=2, slices=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster):
        res = run_study(cfg, backend="dask", chunk_size=1)
    assert res.run["backend"] == "dask"
    assert _strip(res.rows) == _strip(run_study(cfg).rows)


@pytest.mark.slow    # fast sibling: test_cli
def test_csv_round_trip_and_figures(tmp_path):
    from procam.plots.study import save_study_figures

    cfg = StudyConfig("camera", psi=[0.0, 10.0], nu=[-10.0, 10.0], trials=2, slice_angles=[-10, 10])
    res = run_study(cfg)
    path = res.to_csv(tmp_path / "s.csv")
    with path.open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(res.rows) and rows[0]["device"] == "camera"
    back = StudyResult.from_csv(path, cfg)
    psi, nu, a = res.grid("bound_f")
    _, _, b = back.grid("bound_f")
    np.testing.assert_allclose(a, b, rtol=1e-5)
    assert np.all(np.isinf(a[0]))  # psi = 0 is degenerate for (f, alpha)
    assert [r["psi"] for r in back.slice("nu=10")] == [-10.0, 10.0]
    paths = save_study_figures(res, tmp_path)
    assert len(paths) == 5 and all(p.stat().st_size > 5000 for p in paths)


def test_cli(tmp_path):
    from typer.testing import CliRunner

    from procam.cli import app

    runner = CliRunner()
    out = tmp_path / "o"
    r = runner.invoke(app, ["study", "projector", "--grid", "10,20", "--trials", "2", "--slice-grid", "10",
                            "--model-error", "none", "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert (out / "study_projector_none.csv").exists() and (out / "study_projector_none.json").exists()
    assert (out / "study_projector_none_slices.png").exists()
    assert "cells" in r.output
    bad = runner.invoke(app, ["study", "lens", "-o", str(out)])
    assert bad.exit_code == 2 and "'camera', 'projector'" in bad.output
    bad = runner.invoke(app, ["study", "camera", "--grid", "1:2", "-o", str(out)])
    assert bad.exit_code == 2 and "START:STOP:STEP" in bad.output


def test_cli_zero_trials_writes_strict_json(tmp_path):
    """--trials 0 gives NaN medians: the summary must still be valid JSON (null, not NaN)."""
    import json

    from typer.testing import CliRunner

    from procam.cli import app

    out = tmp_path / "o"
    r = CliRunner().invoke(app, ["study", "camera", "--grid", "10", "--trials", "0", "--no-slices",
                                 "--no-figures", "--model-error", "none", "-o", str(out)])
    assert r.exit_code == 0, r.output
    text = (out / "study_camera_none.json").read_text()
    d = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))
    assert d["summary"]["cells"] == 1 and d["config"]["psi"] == [10.0]
    assert not [p for p in out.iterdir() if p.name.startswith(".") and p.name != ".procam-manifest.json"]  # no temp files


@pytest.mark.slow
def test_render_path_one_cell():
    """Full rendering + decoding per trial (camera study; D = 500 mm is enough for the camera corners)."""
    cfg = StudyConfig("camera", trials=2, render=True, model_error="none")
    row = run_cell(cfg, 20.0, 20.0)
    assert row["n_ok"] == 2
    assert row["median_abs_df"] < 10 * row["bound_f"] + 5
