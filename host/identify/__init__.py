"""Identification of the hysteresis models from measured data (scikit-learn style estimators).

``fit(u, y)`` returns the estimator; learned attributes end in ``_``: ``model_`` (the forward
model, a :class:`~edge.hysteresis.base.HysteresisModel` in the state it ended the training data
in), ``fit_seconds_``, ``start_index_`` / ``start_branch_`` (where the memory became known).
"""

from host.identify.dpi import DPIEstimator
from host.identify.mpi import MPIEstimator
from host.identify.pi import PIEstimator
from host.identify.preisach import PreisachEstimator

ESTIMATORS = {
    "pi": PIEstimator,
    "mpi": MPIEstimator,
    "dpi": DPIEstimator,
    "preisach": PreisachEstimator,
}

__all__ = ["ESTIMATORS", "PIEstimator", "MPIEstimator", "DPIEstimator", "PreisachEstimator"]
