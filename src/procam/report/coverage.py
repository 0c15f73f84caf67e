"""How much of each image plane the poses' corners cover (the report's coverage section).

The share of an image inside the union of the poses' corner outlines (their convex hulls,
:func:`procam.reconstruct.board_region`): corners near the edges pin the lens distortion there, and outside
the outlines the model extrapolates. A share, not a verdict: a low one is worth a look at the figure.
"""

from __future__ import annotations

import numpy as np

__all__ = ["coverage_fractions"]


def coverage_fractions(views, cam_size, proj_size=None) -> dict:
    """Share of each image inside the union of the poses' corner outlines (convex hulls).

    Parameters
    ----------
    views : :class:`procam.view.View` sequence; cam_size, proj_size : (width, height).

    Returns
    -------
    ``{"camera": fraction, "projector": fraction}`` (0..1; the projector only with ``proj_size``).
    """
    from ..board import board_region

    out = {}
    for label, key, size in (("camera", "cam_pts", cam_size), ("projector", "proj_pts", proj_size)):
        if size is None:
            continue
        m = np.zeros((int(size[1]), int(size[0])), bool)
        for v in views:
            m |= board_region(getattr(v, key), size)
        out[label] = float(m.mean())
    return out
