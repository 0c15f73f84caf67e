"""procam.plots: save_figure (format from the suffix, atomic, clear error otherwise); no global matplotlib state."""

from pathlib import Path

import pytest

from procam.errors import ProcamError
from procam.plots import save_figure


def _fig():
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    return fig


@pytest.mark.parametrize("name, magic", [("a.png", b"\x89PNG"), ("b.PDF", b"%PDF"), ("c.svg", b"<?xml")])
def test_format_from_suffix(tmp_path, name, magic):
    import matplotlib.pyplot as plt

    n = len(plt.get_fignums())
    path = save_figure(_fig(), tmp_path / "sub" / name)
    assert path.read_bytes().startswith(magic)
    assert [p.name for p in path.parent.iterdir()] == [name]  # no temporary file left
    assert len(plt.get_fignums()) == n  # closed


@pytest.mark.parametrize("name", ["noext", "x.foo"])
def test_unsupported_suffix_is_a_clear_error(tmp_path, name):
    with pytest.raises(ProcamError, match="give a file name ending in one of .*\\.png"):
        save_figure(_fig(), tmp_path / name)
    assert not list(tmp_path.iterdir())


def test_old_import_locations_still_work():
    from procam.plots import decode, experiment

    assert decode.save_figure is save_figure and experiment.save_figure is save_figure


def test_plots_touch_no_global_matplotlib_state(tmp_path):
    """Importing procam.plots imports no matplotlib; drawing and saving figures keeps the user's backend
    (a notebook's inline backend, an application's Qt one) and registers nothing with pyplot."""
    import os
    import subprocess
    import sys

    script = f"""
import sys
import numpy as np
import procam, procam.plots
import procam.plots.correspond, procam.plots.decode, procam.plots.experiment, procam.plots.residuals
import procam.plots.study
assert "matplotlib" not in sys.modules, "import procam.plots imported matplotlib"
import matplotlib
matplotlib.use("pdf")  # the user's choice, not procam's
from procam.plots import save_figure
from procam.plots.residuals import residual_figure
pts = np.array([[10.0, 20.0], [30.0, 40.0]])
fig = residual_figure([{{"name": "a", "cam_pts": pts, "cam_res": pts * 0.01}}], (64, 48))
save_figure(fig, {str(tmp_path / "r.png")!r})
assert matplotlib.get_backend() == "pdf", matplotlib.get_backend()
assert "matplotlib.pyplot" not in sys.modules
print("ok")
"""
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    src = str(Path(__file__).resolve().parents[1] / "src")
    env["PYTHONPATH"] = os.pathsep.join([src, env.get("PYTHONPATH", "")])
    res = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0 and res.stdout.strip() == "ok", res.stderr
    assert (tmp_path / "r.png").read_bytes().startswith(b"\x89PNG")
