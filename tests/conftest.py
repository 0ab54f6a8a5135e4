"""Shared test configuration: matplotlib without a display, the fast tier."""

import matplotlib
import pytest

matplotlib.use("Agg")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark every test not marked ``slow`` as ``fast`` (``pytest -m fast -n auto``)."""
    for item in items:
        if item.get_closest_marker("slow") is None:
            item.add_marker(pytest.mark.fast)
