"""The bounded per-model cache of derived objects (engines, compiled filters)."""

from __future__ import annotations

import gc
import weakref

import pytest

from inference.model_cache import ModelCache


class _Model:
    pass


class _Derived:
    def __init__(self, model: _Model) -> None:
        self.model = model  # a derived object refers to its model, as engines do


def test_value_is_built_once_per_model_and_reused() -> None:
    cache: ModelCache[_Derived] = ModelCache(maxsize=2)
    m = _Model()
    calls = []
    first = cache.get(m, lambda: calls.append(1) or _Derived(m))
    assert cache.get(m, lambda: calls.append(1) or _Derived(m)) is first
    assert calls == [1] and m in cache and _Model() not in cache


def test_least_recently_used_model_is_dropped_and_freed() -> None:
    cache: ModelCache[_Derived] = ModelCache(maxsize=2)
    a, b, c = _Model(), _Model(), _Model()
    for m in (a, b):
        cache.get(m, lambda m=m: _Derived(m))
    del m  # the loop variable refers to b
    cache.get(a, lambda: pytest.fail("a is cached"))  # a is now the most recent
    cache.get(c, lambda: _Derived(c))
    assert a in cache and c in cache and b not in cache and len(cache) == 2
    gone = weakref.ref(b)
    del b
    gc.collect()
    assert gone() is None  # the evicted model is not kept alive by its derived value


def test_many_models_stay_bounded() -> None:
    cache: ModelCache[_Derived] = ModelCache(maxsize=3)
    refs = []
    for _ in range(20):
        m = _Model()
        refs.append(weakref.ref(m))
        cache.get(m, lambda m=m: _Derived(m))
        del m
    gc.collect()
    assert len(cache) == 3 and sum(r() is not None for r in refs) == 3


def test_maxsize_must_be_positive() -> None:
    with pytest.raises(ValueError, match="maxsize"):
        ModelCache(maxsize=0)
