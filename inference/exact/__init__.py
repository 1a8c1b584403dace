"""Exact inference: log-space factors, variable elimination, junction tree, MAP, discrete DBN filtering."""
