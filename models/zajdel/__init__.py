"""Zajdel multi-camera tracker (seeds 000 and 002): re-identification of people across
non-overlapping cameras with an unknown number of people.

Modules: ``data`` (observations), ``path`` (path model), ``params``, ``scores``
(closed-form track and partition scores), ``metrics`` (partition accuracy q, objects,
pairwise F1), ``oracle`` (exact enumeration), ``greedy`` (single-hypothesis baseline),
``simulate`` (office-building generator, SIMULATED data), ``model`` (the slice model
declared with ``dbn``), ``tracker`` (the ADF tracker of seed 002 on
:mod:`inference.adf.driver`; its types in ``adf_types``, step hooks in ``adf_hooks``,
fixed-lag revision in ``adf_lag``, decoding in ``decode``), ``demo``. The same ADF as a
plain numpy loop (baseline and regression oracle) is ``benchmarks._zajdel_numpy_loop``.
"""
