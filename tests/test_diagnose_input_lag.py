"""An input read through a lag of its own (a snubbed or filtered pressure transducer).

The output then leads the recorded input, and a rate term (``branch * speed``) fits that lead:
effect-free records were named ``rate_dependence``. The baseline's actuator grid includes the
inverse of such a lag, so the lead is part of the rig, not an effect.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bench.plants.pulses import muscle_stroke, pulse_pressure
from host.data import Measurement
from host.diagnose import run
from host.diagnose.features import actuator_input, first_order

SNUBBER_S = 0.009  # between the grid's 6 and 12 ms leads: the test is not an exact inversion


def test_a_negative_lag_undoes_a_first_order_lag_exactly():
    rng = np.random.default_rng(0)
    pressure = np.cumsum(rng.normal(size=2000))
    for dt, tau in ((0.002, 0.012), (0.01, 0.006), (0.001, 0.025)):
        read = first_order(pressure, dt, tau)
        assert np.max(np.abs(actuator_input(read, dt, -tau) - pressure)) < 1e-9


def test_leads_shorter_than_half_a_sample_are_not_tried():
    assert min(run.actuator_lags(0.002)) == min(run.ACTUATOR_LAGS_S)
    assert -0.006 not in run.actuator_lags(0.02) and -0.012 in run.actuator_lags(0.02)
    assert all(lag >= 0 or -lag >= 0.01 for lag in run.actuator_lags(0.02))


def _pulses(snubber_s: float) -> Measurement:
    """The pulse-driven muscle (:mod:`bench.plants.pulses`) at 250 Hz for 80 s, its pressure
    recorded through a transducer lag of ``snubber_s``."""
    dt, pressure = pulse_pressure(250.0, 80.0)
    rng = np.random.default_rng(3)
    n = pressure.size
    y = muscle_stroke(pressure) + rng.normal(0.0, 0.01, n)
    u = first_order(pressure, dt, snubber_s) + rng.normal(0.0, 0.002, n)
    return Measurement(np.arange(n) * dt, u, y, {}, source="snubbed pulses")


def _diagnosed(m: Measurement):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run.diagnose(m, progress=False)


def test_a_snubbed_input_is_a_lead_of_the_rig_not_rate_dependence(monkeypatch: pytest.MonkeyPatch):
    d = _diagnosed(_pulses(SNUBBER_S))
    assert d.context.lag_s in (-0.006, -0.012)  # the grid's nearest leads
    assert d.cause == "none"
    assert any("output leads the recorded input" in note for note in d.notes)
    # without the leads the same record is named rate dependence: the guard is what holds it
    monkeypatch.setattr(run, "ACTUATOR_LAGS_S", tuple(lag for lag in run.ACTUATOR_LAGS_S if lag >= 0))
    without = _diagnosed(_pulses(SNUBBER_S))
    assert without.context.lag_s == 0.0
    assert without.cause == "rate_dependence"


def test_a_direct_reading_gets_no_lead():
    assert _diagnosed(_pulses(0.0)).context.lag_s == 0.0
