import os

# One BLAS thread per process: on a loaded 2-core machine OpenBLAS threads oversubscribe the cores and a
# small SVD inside least_squares can take 100x longer.  Must be set before numpy is imported.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import contextlib  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

os.environ.setdefault("MPLBACKEND", "Agg")

SHARED = Path(__file__).resolve().parents[2] / "shared"


@pytest.fixture
def shared_data():
    """Path of ../shared/data, or skip when the shared folder is absent (a user's clone)."""
    path = SHARED / "data"
    if not path.is_dir():
        pytest.skip("../shared/data is not available")
    return path


def write_stack(folder, stack, names=None, ext=".png"):
    """Write a (K, H, W[, 3]) stack as images into ``folder``; returns the paths."""
    import cv2

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    names = names or [f"{i:02d}{ext}" for i in range(len(stack))]
    paths = []
    for name, img in zip(names, stack):
        path = folder / name
        assert cv2.imwrite(str(path), img)
        paths.append(path)
    return paths


def camera_view_of_patterns(w=64, h=48, order="opencv", seed=0, noise=1.0, dtype=np.uint8):
    """A small linear 'capture' of the pattern sequence, pixel for pixel."""
    from procam import patterns

    rng = np.random.default_rng(seed)
    light = patterns.generate(w, h, order).astype(np.float32) / 255.0
    img = 20 + 180 * (0.02 + 0.98 * light) + rng.normal(0, noise, light.shape)
    full = 255 if dtype == np.uint8 else 65535
    return np.clip(np.round(img * full / 255), 0, full).astype(dtype)


def run_cli(args):
    """Run the procam CLI in-process; returns (exit_code, stdout, stderr)."""
    from typer.testing import CliRunner

    from procam.cli import app

    runner = CliRunner()
    res = runner.invoke(app, [str(a) for a in args])
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        raise res.exception
    out = res.stdout
    try:
        err = res.stderr
    except ValueError:
        err = ""
    return res.exit_code, out, err


@pytest.fixture
def forked_reader():
    """A :class:`procam.io.child_reader.ChildReader`, forked beside pytest's threads (the command line forks only
    while it runs one thread; on Python 3.12 and later a fork beside threads warns, which ``when_threaded`` accepts
    here); closed after the test. Skipped off Linux.

    A fork copies every lock as it is at that moment, held or not, and none of the threads that would let go of one.
    The command line forks before OpenCV is loaded; here OpenCV's pool of worker threads has run, and a child that
    inherited a pool lock in use hung in its first ``cv2.integral`` (once in many runs, holding up the whole test
    session).  So OpenCV runs on one thread as the fork happens (its pthreads pool stops and joins its workers; the
    child keeps one thread, this process gets its count back), and a child still running after ``HANG`` seconds is
    killed and the test fails saying so, instead of waiting for ever."""
    import os
    import signal
    import sys
    import threading
    import warnings

    if not sys.platform.startswith("linux"):
        pytest.skip("the child reader forks: Linux only")
    from procam.io.child_reader import ChildReader

    cv2 = sys.modules.get("cv2")
    threads = cv2.getNumThreads() if cv2 is not None else None
    if cv2 is not None:
        cv2.setNumThreads(1)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            reader = ChildReader.start(when_threaded=True)
    finally:
        if cv2 is not None:
            cv2.setNumThreads(threads)
    assert reader is not None
    hung, pid = [], reader.pid

    def kill():  # only the child itself, while not yet reaped (its pid cannot have been reused)
        if pid > 0 and reader.pid == pid:
            hung.append(pid)
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass

    watchdog = threading.Timer(FORKED_READER_HANG, kill)
    watchdog.daemon = True
    watchdog.start()
    yield reader
    watchdog.cancel()
    reader.close()
    if hung:
        pytest.fail(f"the forked child reader (pid {hung[0]}) was still running after {FORKED_READER_HANG} s: killed")


#: Seconds a test's forked child reader may run (its tests take a few).
FORKED_READER_HANG = 240


@pytest.fixture(scope="session")
def paper_capture(tmp_path_factory):
    """One rendered capture (paper preset, recommended pose, default noise, seed 1), written to a folder.

    Rendered once per test session: returns (folder, stack, truth dict, scene).
    """
    from procam import simulate

    scene = simulate.with_board_pose(simulate.preset("paper"), simulate.RECOMMENDED_POSE)
    stack, truth = simulate.render(scene, seed=1)
    folder = tmp_path_factory.mktemp("paper_capture")
    simulate.write_capture(folder, stack, truth)
    return folder, stack, truth, scene


@pytest.fixture(scope="session")
def ideal_capture(tmp_path_factory):
    """Like :func:`paper_capture` with the ``ideal`` preset (single-pose assumptions true)."""
    from procam import simulate

    scene = simulate.with_board_pose(simulate.preset("ideal"), simulate.RECOMMENDED_POSE)
    stack, truth = simulate.render(scene, seed=2)
    folder = tmp_path_factory.mktemp("ideal_capture")
    simulate.write_capture(folder, stack, truth)
    return folder, stack, truth, scene


def fake_pose_folders(monkeypatch, root, *, check_board=None, pass_board=False):
    """Fast CLI tests without rendering: ``pipeline.view_from_folder`` returns, for a folder made by the returned
    ``add(name, view) -> Path``, that View named after the folder (with the command's board when
    ``pass_board``); ``check_board(board)`` sees the board the command passed."""
    from procam import pipeline
    from procam.view import View

    by_name = {}

    def fake(folder, board, projector=None, order=None, **kw):
        if check_board is not None:
            check_board(board)
        v = by_name[Path(folder).name]
        return View(v.obj_pts, v.cam_pts, v.proj_pts, str(folder), v.cam_size, v.proj_size,
                    board=board if pass_board else None), None

    monkeypatch.setattr(pipeline, "view_from_folder", fake)

    def add(name, view):
        (Path(root) / name).mkdir()
        by_name[name] = view
        return Path(root) / name

    return add


def rms(a, b):
    d = np.asarray(a, float) - np.asarray(b, float)
    return float(np.sqrt(np.nanmean(np.sum(d * d, axis=1))))


@contextlib.contextmanager
def verdict_warnings():
    """Collect procam's verdict warnings (weak, degenerate, failed, model error) raised inside instead of failing
    on them (the suite turns every warning into an error): for helpers and tests whose subject is not the verdict
    -- the result carries it, and the test checks it where it matters. Any other warning still fails. Yields the
    list of ``warnings.WarningMessage``."""
    from procam.errors import ProcamWarning

    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("error")
        warnings.simplefilter("always", ProcamWarning)
        yield seen


@contextlib.contextmanager
def expect_warning(category, match=None):
    """``pytest.warns(category, match=match)`` for the one verdict warning a test is about; procam's other verdict
    warnings of the same calls (pytest re-emits what does not match) are recorded, not failures."""
    with verdict_warnings(), pytest.warns(category, match=match) as record:
        yield record


# ------------------------------------------------------------------------------------------------
# the default run: long tests with a sibling in it run with `pytest -m slow`
# ------------------------------------------------------------------------------------------------

#: Parametrised tests whose first case stays in the default run and whose other cases (the same path at other
#: seeds, poses, orders or labellings, each several seconds) run with ``-m slow``.
SLOW_SIBLINGS = (
    "test_real_projector.py::test_a_pose_the_data_cannot_resolve_is_never_good",
    "test_real_projector.py::test_a_known_projector_gives_R_and_T_within_their_std",
    "test_decode.py::test_noise_and_low_contrast",
    "test_export.py::test_rectified_rows_agree_and_hold_the_board_for_any_rig_orientation",
    "test_descriptions.py::test_every_gray_block_decodes_in_the_order_described",
    "test_verdicts_words.py::test_camera_only_photo_and_multi_pose_are_the_same_whatever_the_labelling",
    "test_verdicts_words.py::test_single_pose_is_the_same_whatever_the_boards_labelling",
    "test_advisor.py::test_projector_angles_and_predicted_stds_across_poses",
    "test_single_pose.py::test_an_assumed_u0p_costs_what_it_can",
    "test_single_pose.py::test_fronto_parallel_or_single_axis_camera_pose_is_flagged",
    "test_cli.py::test_gallery_examples_run",
    "test_bad_inputs.py::test_every_pose_option_choice",
    "test_figures.py::test_focal_error_figure_clips_no_point",
    "test_plausibility.py::test_a_pattern_swapped_with_its_inverse_is_named",
    "test_background.py::test_check_fires_on_the_paper_rig",
    "test_background.py::test_check_is_silent_on_the_ideal_rig",
)
#: Long tests whose path the default run covers elsewhere (the test named after each), run with ``-m slow``.
SLOW_COVERED = {
    "test_cli.py::test_demo_runs": "CI runs procam demo itself; test_cli's calibrate end to end",
    "test_experiment.py::test_cli_experiment_report_shows_the_experiments_own_all_pose_calibration":
        "test_experiment.py::test_cli_experiment",
    "test_multi_pose.py::test_joint_refinement_at_least_as_close_as_frozen_stereo":
        "test_multi_pose.py::test_noisy_recovery_and_std",
    "test_report_cli.py::test_calibrate_and_report_a_rendered_capture": "test_report_cli.py::test_report_command",
    "test_background.py::test_every_output_says_what_the_background_estimated":
        "test_background.py::test_calibrate_applies_the_background_only_when_the_view_has_one",
    "test_bad_inputs.py::test_a_second_run_writes_over_its_own_figures_pictures_and_page":
        "test_ownership.py::test_every_writing_command_leaves_every_byte_of_the_users_files_and_its_inputs",
}


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Mark the slow siblings (:data:`SLOW_SIBLINGS` but their first case, :data:`SLOW_COVERED`) ``slow`` before
    ``-m 'not slow'`` deselects."""
    seen = set()
    for item in items:
        node = item.nodeid.split("tests/", 1)[-1]
        base = node.split("[", 1)[0]
        if base in SLOW_COVERED or (base in SLOW_SIBLINGS and base in seen):
            item.add_marker(pytest.mark.slow)
        seen.add(base)


def job_result(client, job: dict, headers: dict, timeout: float = 300.0) -> dict:
    """The app's job ``job`` (the answer of a POST that started it) once it has ended, polled through ``client``
    (starlette's TestClient) with ``headers`` (the token); fails after ``timeout`` seconds."""
    import time

    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        j = client.get(f"/api/jobs/{job['id']}", headers=headers).json()
        if j["state"] != "running":
            return j
        time.sleep(0.1)
    raise AssertionError(f"job {job} did not end within {timeout} s")



def within(seconds: float, fn, *args):
    """``fn(*args)`` in a daemon thread, failing the test when it has not finished after ``seconds`` (a call that
    must answer, not wait); returns what it returned, or the exception it raised."""
    import threading

    out = []

    def run():
        try:
            out.append(fn(*args))
        except Exception as e:  # the caller asserts on it
            out.append(e)

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(seconds)
    assert not t.is_alive(), f"{getattr(fn, '__name__', fn)} did not answer within {seconds} s"
    return out[0]
