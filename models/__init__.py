"""The trackers of the seed papers, each built on ``dbn`` and ``inference``.

``models.available()`` lists the registered trackers and ``models.get(name)`` returns an
entry (seed paper, what it tracks, input formats, ``make`` and ``example``); every tracker
follows the protocol of :mod:`models.protocol`. Importing ``models`` imports no tracker.
"""

from models.registry import available, get

__all__ = ["available", "get"]
