"""Every tracker's config refuses a bad number in any numeric field, naming it.

For each config class (dataclasses check on construction, ``NamedTuple`` configs in their
``validate()``), every field whose default is an int and every one whose default is a
float is given bad values one at a time (:func:`dbn.checks.check_number_fields`): NaN
passed range checks written as ``x < 1`` (``ADFConfig(chunk=nan)``, ``NetworkConfig(radius
=nan)`` ran), 2.5 in an int field ran as 2.5, a string raised Python's ``TypeError`` on
comparison, and 1e300 overflowed once squared. Each must raise a :mod:`dbn.errors` class
whose message names the field.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dbn.checks import check_number_fields
from dbn.errors import DBNError, InputError, ModelError
from models.jorge.config import NetworkConfig
from models.jorge.labels import LabelParams
from models.jorge.online import OnlineConfig
from models.jorge.strokes import StrokeConfig
from models.pathrecovery.filter import FilterConfig
from models.rjmcmc3d.model import TrackerParams
from models.zajdel.adf_types import ADFConfig
from models.zajdel.learnsearch import LearnSearchConfig
from models.zajdel.simulate import OfficeConfig, simulate_office

CONFIGS = [NetworkConfig, OnlineConfig, StrokeConfig, FilterConfig, TrackerParams, ADFConfig,
           LearnSearchConfig]  # fmt: skip


def _numeric_fields(cls) -> list[tuple[str, type]]:
    if dataclasses.is_dataclass(cls):
        defaults = {f.name: f.default for f in dataclasses.fields(cls)}
    else:
        defaults = cls._field_defaults
    return [(name, type(d)) for name, d in defaults.items() if type(d) in (int, float)]


def _make(cls, **change):
    default = cls()
    obj = (dataclasses.replace(default, **change) if dataclasses.is_dataclass(cls)
           else default._replace(**change))  # fmt: skip
    if callable(getattr(obj, "validate", None)):
        obj.validate()
    return obj


@pytest.mark.parametrize("cls", CONFIGS, ids=lambda c: c.__name__)
def test_every_numeric_field_refuses_a_bad_number_naming_it(cls) -> None:
    fields = _numeric_fields(cls)
    assert len(fields) >= 3
    _make(cls)  # the defaults pass
    for name, kind in fields:
        bad = [np.nan, "a", None, True] + ([2.5] if kind is int else [np.inf, -1e300])
        for value in bad:
            with pytest.raises(DBNError, match=name):
                _make(cls, **{name: value})


def test_check_number_fields_reads_the_defaults_types() -> None:
    """An int field takes numpy integers, a float field ints; a field with another default
    (a string, a bool, None, a table) is not read."""

    @dataclasses.dataclass
    class Toy:
        count: int = 3
        scale: float = 1.0
        mode: str = "a"
        flag: bool = False
        table: tuple = ()

    check_number_fields(Toy(count=np.int64(-2), scale=4, mode=5, flag=2.5, table=None))
    for change, needle in (({"count": 3.0}, "Toy.count must be an integer, got 3.0"),
                           ({"scale": 1e101}, "Toy.scale must be a finite number"),
                           ({"scale": np.float32("nan")}, "Toy.scale")):  # fmt: skip
        with pytest.raises(InputError, match=needle):
            check_number_fields(Toy(**change))


@pytest.mark.parametrize(("change", "needle"), [
    ({"num_people": np.nan}, "OfficeConfig.num_people must be an integer"),
    ({"obs_dim": 2.5}, "OfficeConfig.obs_dim must be an integer"),
    ({"num_borders": 0}, "num_borders >= 1"),  # numpy's "high <= 0"
    ({"within_std": 0.0}, "within_std must be > 0"),  # Python's ZeroDivisionError
    ({"arrival_window": -5.0}, "arrival_window must be >= 0"),  # numpy's "high - low < 0"
    ({"travel_cv": 1e300}, "travel_cv must be a finite number"),
])  # fmt: skip
def test_the_office_simulator_names_a_bad_config_field(change, needle) -> None:
    with pytest.raises(ModelError, match=needle):
        simulate_office(0, OfficeConfig(**change))


def test_label_params_name_a_bad_number() -> None:
    """LabelParams(max_group_size=nan) raised numpy's "cannot convert float NaN to
    integer" and 2.5 ran."""
    for value in (np.nan, 2.5):
        with pytest.raises(ModelError, match="LabelParams.max_group_size"):
            LabelParams(max_group_size=value)


def _tuple_fields(cls) -> list[tuple[str, tuple]]:
    """The fields whose default is a non-empty flat tuple of numbers."""
    if dataclasses.is_dataclass(cls):
        defaults = {f.name: f.default for f in dataclasses.fields(cls)}
    else:
        defaults = cls._field_defaults
    return [(n, d) for n, d in defaults.items() if type(d) is tuple and d
            and all(type(v) in (int, float) for v in d)]  # fmt: skip


def _make_any(cls, **change):
    """Build and check a config as its users do (``simulate_office`` reads OfficeConfig,
    ``_check_config`` MCMCConfig)."""
    from models.zajdel.mcmc import MCMCConfig, _check_config

    obj = _make(cls, **change) if cls is not MCMCConfig else MCMCConfig(**change)
    if cls is OfficeConfig:
        simulate_office(0, obj)
    if cls is MCMCConfig:
        _check_config(obj, 10, 1)
    return obj


def _configs_with_tuples():
    from models.zajdel.mcmc import MCMCConfig

    return [c for c in (*CONFIGS, LabelParams, OfficeConfig, MCMCConfig) if _tuple_fields(c)]


@pytest.mark.parametrize("cls", _configs_with_tuples(), ids=lambda c: c.__name__)
def test_every_field_of_numbers_refuses_what_is_not_numbers_naming_it(cls) -> None:
    """Move probabilities, ranges and bins given as text or complex numbers raised numpy's
    ValueError or Python's TypeError (MCMCConfig, OfficeConfig, LabelParams), or were
    accepted (TrackerParams: complex shape_sd and move_probs ran)."""
    for name, default in _tuple_fields(cls):
        _make_any(cls, **{name: list(default)})  # a list, as JSON gives it, passes
        _make_any(cls, **{name: np.asarray(default)})  # and a 1-D array
        n = len(default)
        for value in (("a",) * n, (1 + 0j,) * n, (np.nan,) * n, (True,) * n, "ab",
                      np.ones((n, 1)), 5):  # fmt: skip
            with pytest.raises(DBNError, match=f"{cls.__name__}.{name} must be a sequence"):
                _make_any(cls, **{name: value})
