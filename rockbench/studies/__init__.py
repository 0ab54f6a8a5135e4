"""Studies: pure functions that run scenarios × methods and return typed results.

``compare`` (the paper-style comparison), ``matrix`` (the regression matrix and
its tolerances), ``sweep`` (settings grids and ``tune``), ``spectrum``
(overturning spectra) and ``sensitivity`` (the paper's Table 2 study). They run
through :mod:`rockbench.runner`, evaluate each run with
:func:`rockbench.evaluation.evaluate_run` and record it in the
:class:`rockbench.store.Store`; rendering lives in :mod:`rockbench.report` and
the command-line glue in :mod:`rockbench.cli`.
"""
