"""Assumed-density filtering pieces (seed 002, section 1.2.2): categorical marginals,
Gaussian moment matching, the Normal-Inverse-Wishart KL projection (jax, vmap, jit,
float64) and the Student-t predictive; the generic ADF driver (``driver``: hooks
predict / condition / project, chunked scan, capacity growth, fixed-lag revision),
compacting a hypothesis table by posterior mass (``compact``) and state checkpoints
(``checkpoint``)."""

from inference.adf.categorical import categorical_marginals, mix_categoricals, normalize_log
from inference.adf.compact import compact_rows, prune_rows_by_mass, row_capacity
from inference.adf.gaussian import gaussian_moment_match
from inference.adf.niw import (
    NIW,
    niw_expected_stats,
    niw_from_stats,
    niw_log_evidence_masked_np,
    niw_log_evidence_np,
    niw_predictive_logpdf,
    niw_predictive_logpdf_np,
    niw_project,
    niw_project_cached,
    niw_update,
    niw_update_np,
    student_t_logpdf,
    student_t_logpdf_np,
)

__all__ = [
    "compact_rows",
    "prune_rows_by_mass",
    "row_capacity",
    "categorical_marginals",
    "mix_categoricals",
    "normalize_log",
    "gaussian_moment_match",
    "NIW",
    "niw_expected_stats",
    "niw_from_stats",
    "niw_log_evidence_masked_np",
    "niw_log_evidence_np",
    "niw_predictive_logpdf",
    "niw_predictive_logpdf_np",
    "niw_project",
    "niw_project_cached",
    "niw_update",
    "niw_update_np",
    "student_t_logpdf",
    "student_t_logpdf_np",
]
