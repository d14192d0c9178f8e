"""ClogScope from Python: the strand width under a 3D-printer nozzle from microscope frames,
the pixel scale from reference targets, and the clog physics, through the same functions the
``clogscope`` command line calls.

Frames are NumPy arrays (uint8 or uint16, H×W grey or H×W×3 BGR), read in place. Every number
carries its unit in its name (``width_px``, ``scale_um_per_px``); expected failures come back
as results with a reason (``Measurement.status``), bad input raises ``ValueError`` with the
command line's one-line message.

Start with :func:`measure_frame` (one array), :class:`Tracker` (a video, frame by frame) and
:func:`measure` (files, folders, videos into a pandas table). See docs/python.md.
"""

from ._core import *  # noqa: F401,F403 (the extension's classes and functions)
from ._core import __version__  # noqa: F401
from .api import measure, render, run_experiment  # noqa: F401
from .tables import (prediction_table, read_frames_table, residual_table,  # noqa: F401
                     to_frame, truth_table)
