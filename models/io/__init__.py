"""Readers and writers of the file formats ``dbntrack track`` and ``dbntrack eval`` use.

One module per tracker (``models.io.<name>``), plus :mod:`models.io.table` for the CSV
plumbing they share. Every reader raises a :mod:`dbn.errors` class whose message starts
with ``FILE:LINE:`` on bad input; the formats are documented in ``docs/formats.md``.
"""
