"""Shared fixtures: matplotlib without a display."""

import matplotlib

matplotlib.use("Agg")
