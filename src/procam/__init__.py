"""procam: projector-camera calibration from a single pose of a planar target.

Conventions (see README "Conventions"): pixels are (x, y) = (column, row) with the
origin at the centre of the top-left pixel; ``x_p = R @ x_c + T`` maps camera to
projector coordinates; lengths are in the board's square-size unit; angles are
degrees at the user surface and radians inside the code.
"""

__version__ = "0.1.0"
