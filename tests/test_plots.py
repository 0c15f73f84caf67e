"""procam.plots.save_figure: format from the suffix, atomic, clear error otherwise."""

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
