"""Report: comparison metrics, tables, charts, the HTML/Markdown report, the regression matrix,
sweeps and overturning spectra.

The command-line entry points live in ``command.py`` (compare), ``matrix_command.py``
(matrix, history), ``sweep_command.py`` (sweep, tune) and ``spectrum_command.py``.
"""

from rockbench.metrics import (
    impact_time_errors,
    impact_times,
    max_error,
    peak_ratio,
    peak_relative_error,
    time_to_rest,
)

__all__ = ["impact_time_errors", "impact_times", "max_error", "peak_ratio",
           "peak_relative_error", "time_to_rest"]
