"""A plant family's case: one record's plant, effect, form, protocol, rate, seed and duration."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Case:
    """One record of a family: its plant (core), effect and form, protocol, sample rate [Hz],
    seed and duration [s]."""

    plant: str
    effect: str
    form: str
    protocol: str
    rate_hz: float
    seed: int
    duration_s: float = 150.0

    @property
    def name(self) -> str:
        return f"{self.plant}/{self.effect}:{self.form}/{self.protocol}@{self.rate_hz:g}Hz/s{self.seed}"
