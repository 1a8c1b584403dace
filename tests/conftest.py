"""Shared fixtures: the real-data folder (skipping with a reason when absent)."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("JAX_PLATFORMS", "cpu")

from models import datasets  # noqa: E402


@pytest.fixture(scope="session")
def shared_data():
    """The ``../shared/data`` folder (or ``$DBNTRACK_DATA``); skip the test when absent."""
    path = datasets.data_dir()
    if not path.is_dir():
        pytest.skip(f"real data folder {path} is absent (set DBNTRACK_DATA)")
    return path
