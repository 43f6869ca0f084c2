"""How many operators each model takes: default and stated range (standard library only, for ``--help``)."""

from __future__ import annotations

MODELS = ("pi", "mpi", "dpi", "preisach")
# (default, smallest, largest): plays / digits, or Preisach grid intervals. 100 plays resolve
# 0.5 % of the input range, below what a 12-bit sensor's loop shape shows; 60 Preisach
# intervals are 1830 Everett cells (~30 MB of normal equations), 100 would be 5050 (~200 MB).
OPERATORS = {"pi": (25, 1, 100), "mpi": (25, 1, 100), "dpi": (25, 1, 100), "preisach": (20, 2, 60)}
OPERATORS_HELP = (
    "play operators (pi, mpi), digits (dpi) or grid intervals (preisach); default 25 (pi, mpi, dpi) or 20 "
    "(preisach), range 1-100 (pi, mpi, dpi) or 2-60 (preisach)"
)
