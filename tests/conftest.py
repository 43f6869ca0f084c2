"""Shared fixtures: real data location (skips when absent), leak guard, model factories."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]


def shared_data_dir() -> Path:
    """``../shared/data`` beside the checkout, or ``$PMACTL_SHARED_DATA``."""
    return Path(os.environ.get("PMACTL_SHARED_DATA", REPO.parent / "shared" / "data"))


@pytest.fixture
def shared_data() -> Path:
    """The real measured data; the test is skipped when it is not on this machine."""
    root = shared_data_dir()
    if not root.is_dir():
        pytest.skip(f"real data not found at {root} (a user's clone has no ../shared)")
    return root


@pytest.fixture(autouse=True)
def no_leaked_threads():
    """Fail a test that leaves threads running (pymodbus-style leak guard)."""
    before = set(threading.enumerate())
    yield
    leaked = [t for t in threading.enumerate() if t not in before and t.is_alive()]
    assert not leaked, f"test leaked threads: {leaked}"


def random_walk(rng: np.random.Generator, n: int, lo: float, hi: float, step: float) -> np.ndarray:
    """A bounded random walk with many reversals (minor loops of all sizes)."""
    u = np.empty(n)
    value = (lo + hi) / 2
    for i in range(n):
        value = min(hi, max(lo, value + rng.normal(0.0, step)))
        u[i] = value
    return u
