"""The rig calibration file now lives with every other file procam reads or writes: :mod:`procam.io.rig`.  Its
names stay importable from here."""

from ..io.rig import (RIG_CONVENTIONS, is_rig_calibration, load_rig_calibration, load_rig_document,  # noqa: F401
                      rig_to_dict, save_rig_calibration)

__all__ = ["rig_to_dict", "save_rig_calibration", "load_rig_document", "load_rig_calibration", "is_rig_calibration",
           "RIG_CONVENTIONS"]
