"""Properties of the sixth (blind4) held-out plant family; the diagnosis is never run here.

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: effect free records carry the rig
confounds; creep forms keep moving in a hold and the core alone settles; masing and stoner cores
have return point memory; protocols start vented sweep the range early and then keep covering
it.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    engine,
)
from bench.plants.blind4_cores import BLIND4_CORES, draw_params, masing, stoner_crimps
from bench.plants.blind4_effects import (
    BLIND4_FORMS,
    draw_effect_params,
    render,
)
from bench.plants.blind4_family import (
    BLIND4_PLANTS,
    SPEC,
)
from bench.plants.blind4_protocols import BLIND4_PROTOCOLS, with_s_sweep
from bench.plants.blind4_rig import rig_reading, supply_droop
from bench.plants.case import Case
from bench.plants.properties import (
    step_and_hold,
)
from bench.plants.visibility import rms

DURATION_S = 40.0
CASES = engine.cases(SPEC, DURATION_S)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("plant", BLIND4_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """Supply droop, guide play, mounting plate and the transducer's errors are in every record."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    params, dt = sim["truth"]["plant_parameters"], 1.0 / case.rate_hz
    core = BLIND4_CORES[plant]
    droop = supply_droop(sim["u"], dt, params)
    assert 0.003 <= float(np.max(1.0 - droop[sim["u"] > 0] / sim["u"][sim["u"] > 0])) <= 0.015
    confound = sim["off"] - core(sim["u"], dt, params)
    assert 0.05 <= rms(confound) <= 1.5  # mm: droop, play, plate and transducer together
    still = rig_reading(np.full(int(200.0 / dt), 10.0), dt, params) - 10.0  # a still stroke, 200 s
    spikes = np.abs(still - np.median(still)) > 0.25
    assert 1 <= np.count_nonzero(spikes) <= 30  # rare spikes
    calm = still[~spikes]
    assert 0.005 <= float(np.std(calm)) <= 0.3  # the offset wanders and the 1/f noise jitters
    slow, fast = np.std(np.diff(calm[:: int(5.0 / dt)])), np.std(np.diff(calm))
    assert slow > fast  # the wander is slow: more change over 5 s than from sample to sample


@pytest.mark.parametrize("plant", BLIND4_PLANTS)
def test_creep_forms_keep_moving_in_a_hold_and_the_core_alone_settles(plant: str) -> None:
    rng = np.random.default_rng(5)
    dt, peak = 0.01, 4.0
    params = draw_params(plant, rng, peak)
    u = step_and_hold(peak, dt)
    base = BLIND4_CORES[plant](u, dt, params)
    span = float(np.ptp(base))
    i10, i28 = int(10.0 / dt), int(28.0 / dt)
    assert abs(base[i28] - base[i10]) < 0.01 * span  # the effect-free core settles
    still = np.zeros_like(u)
    off = render(BLIND4_CORES[plant], params, u, dt, "none", {}, still, still + 22.0)
    for form in BLIND4_FORMS["creep"]:
        q = draw_effect_params("creep", form, rng)
        change = render(BLIND4_CORES[plant], params, u, dt, form, q, still, still + 22.0) - off
        assert change[i10] - change[i28] > 0.003 * span, form  # still lengthening 8-26 s after the step


def _excursion(dt: float, peak: float) -> np.ndarray:
    """0 -> 0.8 -> 0.3 -> 0.6 -> 0.45 -> 0.6 -> 0.2 ``peak``: a minor loop inside a branch."""
    knots = np.array([0.0, 0.8, 0.3, 0.6, 0.45, 0.6, 0.2]) * peak
    return np.concatenate([np.linspace(a, b, int(round(8.0 / dt)))[1:] for a, b in zip(knots[:-1], knots[1:])])


def test_masing_and_stoner_cores_have_return_point_memory() -> None:
    """Leaving a branch for a minor loop and coming back to the reversal point returns to the
    same output, and the way down afterwards is the way down without the minor loop (wiping out)."""
    dt, peak = 0.005, 4.0
    p = _excursion(dt, peak)
    n = int(round(8.0 / dt)) - 1
    a, b = 3 * n - 1, 5 * n - 1  # the first and the second arrival at 0.6 peak
    h = masing(p, 0.2, 0.3)
    assert h[b] == pytest.approx(h[a], abs=1e-9)
    direct = masing(np.concatenate([p[: a + 1], p[b + 1 :]]), 0.2, 0.3)
    assert np.allclose(direct[a + 1 :], h[b + 1 :], atol=1e-9)
    params = draw_params("stoner_crimps", np.random.default_rng(8), peak)
    params["tau_valve_s"] = 1e-6  # the pressure is the command: no valve lag between the visits
    y = stoner_crimps(p, dt, params)
    assert y[b] == pytest.approx(y[a], abs=1e-6)
    direct_y = stoner_crimps(np.concatenate([p[: a + 1], p[b + 1 :]]), dt, params)
    assert np.allclose(direct_y[a + 1 :], y[b + 1 :], atol=1e-6)


@pytest.mark.parametrize("protocol", list(BLIND4_PROTOCOLS))
def test_protocols_start_vented_sweep_the_range_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 72.0, 4.0
    u = with_s_sweep(protocol, 60.0, dt, peak, np.random.default_rng(2))
    assert u.size == 4320 and np.all(np.isfinite(u)) and np.all(u[:36] == 0.0)
    early = int(0.15 * u.size)
    assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.97 * peak
    body = u[early:]
    assert np.ptp(body) > 0.5 * peak
    crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
    assert crossings >= 4  # the range is covered again and again, not once
