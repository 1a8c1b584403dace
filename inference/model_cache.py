"""A bounded per-model cache for derived objects (compiled plans, jitted filters, engines).

Engines keep what they derive from a model (a compiled clique tree, a jitted particle
filter, a Rao-Blackwellised layout) so that repeated calls on the same model reuse it.
Those objects refer to the model, so a ``weakref.WeakKeyDictionary`` keyed by the model
never lets it go (the value keeps its own key alive). :class:`ModelCache` instead holds at
most ``maxsize`` models, least recently used dropped first: memory stays bounded however
many models a long session builds, and the models in use keep their compiled code.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from typing import Any, Generic, TypeVar

__all__ = ["ModelCache"]

V = TypeVar("V")


class ModelCache(Generic[V]):
    """Per-model values keyed by model identity, at most ``maxsize`` models (LRU).

    ``get(model, make)`` returns the value stored for ``model`` (the same object, not an
    equal one), building it with ``make()`` on a miss. The model is held with its value,
    so its ``id`` cannot be reused while it is cached.
    """

    def __init__(self, maxsize: int = 8) -> None:
        if maxsize < 1:
            raise ValueError(f"maxsize must be >= 1, got {maxsize}")
        self.maxsize = maxsize
        self._items: OrderedDict[int, tuple[Any, V]] = OrderedDict()

    def get(self, model: Any, make: Callable[[], V]) -> V:
        key = id(model)
        found = self._items.get(key)
        if found is not None:
            self._items.move_to_end(key)
            return found[1]
        value = make()
        self._items[key] = (model, value)
        while len(self._items) > self.maxsize:
            self._items.popitem(last=False)
        return value

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, model: Any) -> bool:
        found = self._items.get(id(model))
        return found is not None and found[0] is model

    def clear(self) -> None:
        self._items.clear()
