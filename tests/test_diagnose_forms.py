"""Forms of a cause that the record's own time scale sets: the dead-time grid in samples and what is
left of the baseline's actuator lag beside a dead time (unit checks), a dead time of a few
samples of a fast record; and two rate effects no rate form fits (known misses): a viscoelastic
branch (a standard linear solid) and a drag that saturates with speed.

Each plant is the plain pulse-driven muscle of :mod:`bench.plants.pulses` with one effect added;
what is checked is the verdict and the form found, not a gain.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bench.plants.pulses import muscle_stroke, pulse_pressure, pulse_record
from host.data import Measurement
from host.diagnose import run
from host.diagnose.candidates import DELAY_RATIO, MIN_DELAY_SAMPLES, _lag_left, delay_grid
from host.diagnose.features import first_order


def _diagnosed(m: Measurement):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run.diagnose(m, progress=False)


@pytest.mark.parametrize("rate_hz", [44.0, 250.0, 1000.0, 10_000.0])
def test_the_dead_time_grid_is_whole_samples_from_three_up_about_a_third_apart(rate_hz):
    dt = 1.0 / rate_hz
    grid = np.array(delay_grid(dt, 20.0))
    samples = grid / dt
    assert np.allclose(samples, np.round(samples)) and round(samples[0]) == MIN_DELAY_SAMPLES
    assert np.all(np.diff(samples) >= 1) and np.all(samples[1:] / samples[:-1] <= DELAY_RATIO * 1.15)
    assert grid[-1] <= 0.5 and grid[-1] * DELAY_RATIO > 0.5 - dt
    assert delay_grid(dt, 2 * dt) == []  # a record too short for three samples of delay


def test_what_is_left_of_the_baseline_lag_after_a_dead_time_is_on_its_grid():
    class Ctx:
        lag_rows = {lag: None for lag in run.ACTUATOR_LAGS_S}
        lag_s = 0.1

    assert _lag_left(Ctx(), 0.03) == 0.05  # type: ignore[arg-type]
    assert _lag_left(Ctx(), 0.1) == 0.0  # type: ignore[arg-type]
    assert _lag_left(Ctx(), 0.3) == 0.0  # type: ignore[arg-type]
    Ctx.lag_s = -0.012  # a lead: no lag to take over, the lead is kept
    assert _lag_left(Ctx(), 0.03) == -0.012  # type: ignore[arg-type]
    Ctx.lag_s = 0.0
    assert _lag_left(Ctx(), 0.03) == 0.0  # type: ignore[arg-type]


def test_a_dead_time_of_six_samples_at_one_kilohertz_is_named():
    """Under the 10 ms a grid in seconds began at: 6 ms at 1 kHz (the grid's nearest is 5 or 7 ms)."""
    dt, pressure = pulse_pressure(1000.0, 25.0)
    stroke = muscle_stroke(pressure)
    late = np.r_[np.full(6, stroke[0]), stroke[:-6]]
    d = _diagnosed(pulse_record(dt, pressure, late, "6 ms dead time"))
    assert d.cause == "transport_delay"
    assert d.extended_model is not None and d.extended_model["dead_time_s"] in (0.005, 0.007)


def _dragged(x: np.ndarray, dt: float, hold_mm: float, knee_mm_s: float) -> np.ndarray:
    """``x`` behind a drag ``hold tanh(v / knee)``, ``v`` the output's own speed: each step solves
    ``y = x - hold tanh((y - y_prev) / (dt knee))`` (increasing in ``y``) by bisection."""
    y = np.empty_like(x)
    y[0] = x[0]
    for i in range(1, x.size):
        lo, hi = x[i] - hold_mm, x[i] + hold_mm
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            if mid - x[i] + hold_mm * np.tanh((mid - y[i - 1]) / (dt * knee_mm_s)) > 0:
                hi = mid
            else:
                lo = mid
        y[i] = 0.5 * (lo + hi)
    return y


def _viscoelastic(x: np.ndarray, dt: float, share: float, tau_s: float) -> np.ndarray:
    """``x`` through a standard linear solid: ``share`` of it follows through a first-order
    relaxation of ``tau_s``, the rest at once (a rubber bladder's viscoelastic branch)."""
    return x - share * (x - first_order(x, dt, tau_s))


# v12 tried the element itself as a third rate form: relaxations of the hysteresis output at
# 0.03, 0.1 and 0.3 s, shares >= 0. It named both records here (+78 %, +66 %) and the drag below
# (+35 %), but on the ten older families' 595 records it named 4 more rate effects and raised 3
# more false alarms (blind4 0 -> 1/20, blind5 0 -> 2/20): against an all-pole baseline a partial
# fast lag also fits the rigs' own mechanics (effect-free gains up to +55 %); half of its new
# verdicts wrong, so it was not kept
VISCOELASTIC_MISS = (
    "known (v12): a partial fast lag after the hysteresis is a linear element with a zero, which the "
    "rigs' mechanics also are; a form for it named 4 more effects and 3 more false alarms, so none is kept"
)


@pytest.mark.xfail(strict=True, raises=AssertionError, reason=VISCOELASTIC_MISS)
@pytest.mark.parametrize(("share", "tau_s"), [(0.05, 0.1), (0.1, 0.03)])
def test_a_viscoelastic_branch_is_named_rate_dependence(share, tau_s):
    """A bladder whose stroke follows 5-10 % of each pressure step through a 30-100 ms relaxation:
    the stroke shrinks and the loop opens with speed. The rate forms gain +2.5 % and +9.6 %."""
    dt, pressure = pulse_pressure(200.0, 60.0)
    stroke = _viscoelastic(muscle_stroke(pressure), dt, share, tau_s)
    d = _diagnosed(pulse_record(dt, pressure, stroke, "viscoelastic"))
    assert d.cause == "rate_dependence"


@pytest.mark.xfail(
    strict=True,
    raises=AssertionError,
    reason="known (v11): a drag form tanh(v / v_knee) named this (+38 %) but cost 3-5 false alarms on the "
    "nine families' effect-free records, so it was dropped; the two rate forms gain 3 % here; " + VISCOELASTIC_MISS,
)
def test_a_drag_that_saturates_with_speed_is_named_rate_dependence():
    """An eddy-current or viscous brake that slips at its hold: 1.5 % of the stroke's span. v|v|
    friction and the speed-weighted loop do not fit a lag that stops growing with speed."""
    dt, pressure = pulse_pressure(200.0, 60.0)
    stroke = muscle_stroke(pressure)
    knee = 0.3 * float(np.percentile(np.abs(np.gradient(stroke, dt)), 95))
    d = _diagnosed(pulse_record(dt, pressure, _dragged(stroke, dt, 1.5, knee), "braked"))
    assert d.cause == "rate_dependence"


def test_the_same_muscle_without_an_effect_is_none():
    dt, pressure = pulse_pressure(200.0, 60.0)
    assert _diagnosed(pulse_record(dt, pressure, muscle_stroke(pressure), "plain")).cause == "none"
