"""NetworkConfig's palette tables given as arrays (what a fit or ``np.load`` returns)."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import ModelError
from models.jorge.config import NetworkConfig

TABLES = ("palette_gain_table", "palette_missing_table", "palette_count_table",
          "palette_gain_bins")  # fmt: skip


@pytest.mark.parametrize("name", TABLES)
def test_a_table_given_as_an_array_is_the_same_config(name):
    """An array's truth value raised numpy's "ambiguous" ValueError in the checks; the
    array is kept as nested tuples, so the config equals the one built from tuples."""
    default = NetworkConfig()
    table = np.asarray(getattr(default, name))
    cfg = NetworkConfig(**{name: table})
    assert cfg == default and isinstance(getattr(cfg, name), tuple)
    assert np.array_equal(np.asarray(getattr(cfg, name)), table)


@pytest.mark.parametrize("name", ["palette_gain_table", "palette_missing_table",
                                  "palette_gain_bins"])  # fmt: skip
def test_a_complex_table_is_refused_naming_it(name):
    """A complex table was refused as "got shape (0,)", and complex bins were accepted."""
    table = np.asarray(getattr(NetworkConfig(), name), dtype=float) + 0j
    needle = "must be a sequence of finite numbers" if table.ndim == 1 else "holds complex"
    with pytest.raises(ModelError, match=f"NetworkConfig.{name} {needle}"):
        NetworkConfig(**{name: table})
