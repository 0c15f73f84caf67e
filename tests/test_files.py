"""File plumbing: atomic writes, full-scale detection (procam.io.files)."""

import numpy as np
import pytest

from procam.io import files as _files


def test_atomic_write_leaves_nothing_on_error(tmp_path):
    target = tmp_path / "out.json"
    with pytest.raises(RuntimeError):
        with _files.atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("boom")
    assert not target.exists() and not list(tmp_path.iterdir())


def test_full_scale_of_bit_depths():
    assert _files.full_scale_of(np.zeros((2, 2), np.uint8)) == 255
    assert _files.full_scale_of(np.full((2, 2), 1000, np.uint16)) == 1023
    assert _files.full_scale_of(np.full((2, 2), 4095, np.uint16)) == 4095
    assert _files.full_scale_of(np.full((2, 2), 4096, np.uint16)) == 16383
    assert _files.full_scale_of(np.full((2, 2), 65535, np.uint16)) == 65535
