"""The trackers of the seed papers, each built on ``dbn`` and ``inference``."""
