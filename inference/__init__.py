"""Inference engines: how to answer questions about a model. Knows nothing of tracking.

Imports ``dbn`` only (never ``models``).

Importing this package switches jax to 64-bit mode (``jax_enable_x64``): filters run in
float64 unless a benchmark shows float32 keeps the accuracy, and float32 is then asked
for explicitly by dtype.
"""

import jax

jax.config.update("jax_enable_x64", True)
