"""The board's geometry (procam.board): Board, object points and the one board-region mask."""

import numpy as np
import pytest

from procam.board import Board, board_outline, board_region, object_points
from procam.errors import ProcamError


def test_board_and_object_points():
    b = Board(10, 6, 24.0)
    obj = b.object_points()
    assert obj.shape == (60, 3) and np.allclose(obj.mean(0), 0)
    assert np.allclose(obj[1] - obj[0], [24.0, 0, 0]) and np.allclose(obj[10] - obj[0], [0, 24.0, 0])
    assert np.array_equal(obj, object_points(10, 6, 24.0))
    with pytest.raises(ProcamError, match="inner corners"):
        Board(2, 6, 24.0)


def test_board_region_follows_the_sub_pixel_corners():
    # a 4 x 3 grid of corners at quarter pixels (a 30 x 20 px rectangle)
    x, y = np.meshgrid(np.linspace(10.25, 40.25, 4), np.linspace(5.75, 25.75, 3))
    c = np.column_stack([x.ravel(), y.ravel()])
    m = board_region(c, (64, 32))
    assert m.shape == (32, 64) and m.dtype == bool
    ys, xs = np.nonzero(m)
    assert (xs.min(), xs.max(), ys.min(), ys.max()) == (10, 40, 6, 26) and m.sum() == 31 * 21
    # moved by a quarter pixel (corners that round to the same whole pixels), the region moves by one pixel
    moved = board_region(c + [0.25, 0.0], (64, 32))
    assert np.array_equal(np.round(c + [0.25, 0.0]), np.round(c))
    assert np.array_equal(moved[:, 1:], m[:, :-1]) and moved.sum() == m.sum()
    # NaN rows are ignored, fewer than 3 corners give nothing, shrink pulls towards the centroid
    assert np.array_equal(board_region(np.vstack([c, [np.nan, np.nan]]), (64, 32)), m)
    assert not board_region(c[:2], (64, 32)).any()
    assert board_region(c, (64, 32), shrink=0.5).sum() < 0.3 * m.sum()
    assert board_region(c, (64, 32), shrink=-0.2).sum() > m.sum()


def test_board_outline_is_the_convex_hull():
    c = np.array([[0, 0], [10, 0], [10, 5], [0, 5], [5, 2], [np.nan, 1]], float)
    out = board_outline(c)
    assert out.shape == (4, 2)
    assert {tuple(p) for p in out} == {(0, 0), (10, 0), (10, 5), (0, 5)}
    assert board_outline(c[:2]).shape == (0, 2)


def test_a_renumbering_rewords_the_rejected_corners_from_the_data_not_the_text():
    """Rejected corners are data (indices, residuals, the rule); their message is worded from the data again in the
    given numbering, and nothing else in a text changes (a number in another message that looks like a corner
    reference stays as it is)."""
    from types import SimpleNamespace

    from procam.board.labelling import Labelling, _reworded
    from procam.verdict import rejection_message

    order = np.array([3, 0, 2, 1])  # canonical corner k is the given corner order[k]
    lab = Labelling(order, np.eye(3))
    words = {"name": "p", "what": "camera", "n_valid": 4, "n_used": 2, "threshold_px": 1.5, "floor_px": 0.5,
             "k": 5.0, "max_list": 8}
    sol = SimpleNamespace(info={"rejection": words}, rejected=np.array([0, 3]),
                          rejected_residuals_px=np.array([2.0, 7.5]))
    changes = lab.given_words(sol)
    (old, new), = changes.items()
    assert "#3 (7.5 px), #0 (2.0 px)" in old and "#1 (7.5 px), #3 (2.0 px)" in new
    assert new == rejection_message(np.array([3, 1]), sol.rejected_residuals_px, words)
    other = "pose 'q': frames #0 (white) look swapped"
    assert _reworded((old, other, f"weak: {old}"), changes) == (new, other, f"weak: {new}")
