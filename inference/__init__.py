"""Inference engines: how to answer questions about a model. Knows nothing of tracking.

Imports ``dbn`` only (never ``models``).

Importing this package (or any module of the library) leaves jax's global configuration
alone: it does NOT switch on ``jax_enable_x64``. Each engine chooses its float dtype
explicitly: filters run in float64 by default and enter jax's 64-bit mode themselves for
the duration of a call (:mod:`inference.precision`); float32 is asked for by ``dtype``
where a benchmark shows it keeps the accuracy.
"""


# --- lazy entry points (issue 11): ``inference.filter`` without importing every engine ---
__all__ = ["filter", "online_filter", "method_options"]


def __getattr__(name: str):
    if name in __all__:
        from inference import api

        return getattr(api, name)
    raise AttributeError(f"module 'inference' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The lazy entry points with the module's own names (tab completion shows them)."""
    return sorted({*globals(), *__all__})
