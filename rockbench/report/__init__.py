"""Report: rendering of study results (tables, figures, HTML/Markdown documents, CSV,
JUnit XML, terminal grids). Nothing here runs an engine or computes a metric:
studies (:mod:`rockbench.studies`) hand it typed results.
"""
