"""The one exception hierarchy of pmactl.

Every error derives from :class:`PmactlError` and also from the matching builtin, so callers
can catch either. Messages name the object at fault and the fix.
"""

from __future__ import annotations


class PmactlError(Exception):
    """Base of every error pmactl raises on purpose."""


class DataError(PmactlError, ValueError):
    """Measured data that cannot be used as given (missing columns, NaN, bad sampling)."""


class ModelError(PmactlError, ValueError):
    """Model parameters that are invalid (non-increasing thresholds, non-invertible weights)."""


class BundleError(PmactlError, ValueError):
    """A model bundle that is missing, corrupt or of the wrong kind."""


class BusError(PmactlError, OSError):
    """A transfer on a hardware bus failed (NACK, I/O error, timeout, corrupt frame)."""


class ConfigError(PmactlError, ValueError):
    """A rig configuration that cannot be run (unknown key, missing calibration, impossible rate)."""
