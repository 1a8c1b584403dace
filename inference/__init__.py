"""Inference engines: how to answer questions about a model. Knows nothing of tracking.

Imports ``dbn`` only (never ``models``).

Importing this package switches jax to 64-bit mode (``jax_enable_x64``): filters run in
float64 unless a benchmark shows float32 keeps the accuracy, and float32 is then asked
for explicitly by dtype.
"""

import jax

jax.config.update("jax_enable_x64", True)


# --- lazy entry points (issue 11): ``inference.filter`` without importing every engine ---
def __getattr__(name: str):
    if name in ("filter", "online_filter"):
        from inference import api

        return getattr(api, name)
    raise AttributeError(f"module 'inference' has no attribute {name!r}")
