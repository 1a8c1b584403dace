"""Inference engines: how to answer questions about a model. Knows nothing of tracking.

Imports ``dbn`` only (never ``models``).
"""
