"""The seed paper's analyses, reproduced: the simulation study and the real-data experiment.

These are procam's answer to "does the method do what the paper says?", not steps of a calibration;
import the module you need:

* :mod:`procam.paper.study` - the simulation sweep of |Δf| over the board's rotation (ψ, ν) relative
  to a device, with the Cramér–Rao bound per cell (``procam study``);
* :mod:`procam.paper.experiment` - single-pose calibration of every pose against multi-pose
  calibrations of every pose set (``procam experiment``), and :mod:`procam.paper.report`, its
  markdown / CSV / JSON / figure report.
"""
