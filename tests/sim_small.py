"""A small rendered capture shared by the reconstruction and export tests (rendered once per process).

The paper rig with a 640x400 camera (half the focal length, the same field of view) and a stronger
division distortion, so a render takes about a second.
"""

from __future__ import annotations

import functools

import numpy as np


@functools.lru_cache(maxsize=None)
def small_scene():
    from procam import simulate

    sc = simulate.preset("paper")
    f = 0.5
    K = np.array(sc.K_cam, float)
    K[0, 0] *= f
    K[1, 1] *= f
    K[0, 2] = (K[0, 2] + 0.5) * f - 0.5
    K[1, 2] = (K[1, 2] + 0.5) * f - 0.5
    small = sc.replace(cam_size=(640, 400), K_cam=K, cam_dist_coeffs=(-4e-7, 0.0), supersample=2, name="small")
    return simulate.with_board_pose(small, simulate.RECOMMENDED_POSE)


@functools.lru_cache(maxsize=None)
def small_capture():
    """(scene, stack (46, 400, 640) uint8, truth dict, DecodeResult) of :func:`small_scene`, seed 3."""
    from procam import decode, patterns, simulate

    scene = small_scene()
    stack, truth = simulate.render(scene, seed=3)
    ps = patterns.pattern_set(*scene.proj_size, "opencv")
    return scene, stack, truth, decode.decode(stack, ps)
