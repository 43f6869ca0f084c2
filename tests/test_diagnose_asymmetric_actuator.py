"""An actuator that fills and vents through different lags (``Rules.asymmetric_actuator``, off)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from host.data import Measurement
from host.diagnose.actuator import fill_vent_lagged, with_actuator
from host.diagnose.features import first_order
from host.diagnose.rules import RULES
from host.diagnose.runs import run_set
from tests.test_diagnose_v3 import RATE_HZ, noisy, pi_core, rested_cycle


def test_equal_lags_are_one_first_order_lag():
    u = np.repeat([0.0, 1.0, 0.2, 0.8], 200)
    assert np.allclose(fill_vent_lagged(u, 0.01, 0.1, 0.1), first_order(u, 0.01, 0.1))


def test_a_step_up_follows_the_fill_lag_and_a_step_down_the_vent_lag():
    dt, fill, vent = 0.01, 0.05, 0.2
    u = np.r_[np.zeros(10), np.ones(300), np.zeros(300)]
    p = fill_vent_lagged(u, dt, fill, vent)
    k = int(round(fill / dt))
    assert p[10 + k - 1] == pytest.approx(1 - np.exp(-1), abs=0.01)  # one fill time constant after the rise
    k = int(round(vent / dt))
    assert p[310 + k - 1] == pytest.approx(np.exp(-1), abs=0.01)  # one vent time constant after the fall


def test_a_valve_that_vents_slower_than_it_fills_is_found():
    """Runs of a play through a valve filling in 20 ms and venting in 170 ms: the switch chooses
    the 170 ms vent beside the symmetric choice (50 ms) as the fill, and says so. The search keeps
    one lag of the pair at the symmetric choice, so the true 20 ms fill is not reached."""
    rng = np.random.default_rng(5)
    runs = []
    for i in range(10):
        t, u = rested_cycle(5 + i, rng)
        pressure = fill_vent_lagged(u, 1 / RATE_HZ, 0.02, 0.17)
        runs.append(Measurement(t, u, noisy(pi_core(pressure, 5), rng), {}, f"run{i}.csv"))
    rs = run_set(runs, RULES.max_rows, RULES.min_samples)
    out = with_actuator(rs, replace(RULES, asymmetric_actuator=True))
    assert out.notes[-1].startswith(
        "the hysteresis is driven by the input through a lag of 50 ms while it fills and 170 ms"
    )
    assert out.input_lag_s == pytest.approx(0.05)
    assert "a lag of 50 ms (the actuator" in with_actuator(rs, RULES).notes[-1]
