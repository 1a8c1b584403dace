"""Streams of the default office with people entering and leaving (SIMULATED data).

:func:`models.zajdel.simulate.simulate_office` already lets people enter (each at a
uniform time over ``arrival_window``) and leave (after their last pass); the default
config has all 5 people inside for the whole 70 observations. :func:`stream_config`
keeps every other knob of the default office (7 cameras, 9-D appearance, separability
1.0, travel cv 0.5) and the default's 14 passes per person, and spreads the arrivals of
``num_obs / 14`` people so that about ``present`` people are inside at once on average
(the default office's 5), as :func:`models.zajdel.simulate.large_config` does for the
large setting. The stream's length then grows by new people, not by longer tracks.
"""

from __future__ import annotations

import numpy as np

from dbn.errors import ModelError
from models.zajdel.simulate import OfficeConfig, default_config

__all__ = ["stream_config"]


def stream_config(num_obs: int = 1000, passes: int = 14, present: float = 5.0) -> OfficeConfig:
    """Office config of a stream of ``num_obs`` observations (rounded down to a multiple
    of ``passes``), ``passes`` per person, about ``present`` people inside at once."""
    if num_obs < passes or passes < 1 or not present > 0:
        raise ModelError(
            f"stream_config: need num_obs >= passes >= 1 and present > 0, "
            f"got num_obs={num_obs}, passes={passes}, present={present}"
        )
    base = default_config()
    people = num_obs // passes
    visit = passes * (np.mean(base.travel_mean_range) + np.mean(base.dwell_range))
    window = max(people * visit / present - visit, 1.0)
    return base._replace(num_people=people, num_obs=people * passes, arrival_window=float(window))
