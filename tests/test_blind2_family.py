"""Properties of the fourth (blind2) held-out plant family; the diagnosis is never run here.

Short records (40 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, every protocol-rate pair), determinism by seed, finite quantised
records, every effect visible (>= 5x noise) yet modest (<= 12 % of span), columns that move in
every record and do nothing unless they are the effect (and do something when they are), the
memory known early (full range in the first 15 %), delays that lag, creep that keeps moving
in a hold, rate forms that grow with speed, and each core's loop (closed, 3-20 % wide).
"""

from __future__ import annotations

from functools import cache, partial
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    engine,
)
from bench.plants.blind2_cores import BLIND2_CORES, draw_params
from bench.plants.blind2_effects import BLIND2_FORMS, draw_effect_params, render
from bench.plants.blind2_family import (
    BLIND2_PLANTS,
    SPEC,
)
from bench.plants.blind2_protocols import BLIND2_PROTOCOLS, with_range_check
from bench.plants.case import Case
from bench.plants.properties import (
    assert_closed_loop_3_to_20_percent_wide,
    slow_and_fast_triangles,
    step_and_hold,
)

DURATION_S = 40.0
CASES = engine.cases(SPEC, DURATION_S)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("plant", BLIND2_PLANTS)
def test_creep_forms_keep_moving_in_a_hold_and_the_core_alone_settles(plant: str) -> None:
    rng = np.random.default_rng(5)
    dt, peak = 0.01, 4.0
    params = draw_params(plant, rng, peak)
    u = step_and_hold(peak, dt)
    base = BLIND2_CORES[plant](u, dt, params)
    span = float(np.ptp(base))
    i10, i28 = int(10.0 / dt), int(28.0 / dt)
    assert abs(base[i28] - base[i10]) < 0.01 * span  # the effect-free rig settles (tails < 4 s)
    still = np.zeros_like(u)
    for form in BLIND2_FORMS["creep"]:
        q = draw_effect_params("creep", form, rng)
        on = render(BLIND2_CORES[plant], params, u, dt, form, q, still, still + 22.0, base)
        assert on[i28] - on[i10] > 0.003 * span, form  # still contracting 8-26 s after the step


@pytest.mark.parametrize("plant", BLIND2_PLANTS)
def test_rate_forms_grow_with_the_input_speed(plant: str) -> None:
    rng = np.random.default_rng(6)
    dt, peak = 0.005, 4.0
    params = draw_params(plant, rng, peak)
    for form in BLIND2_FORMS["rate_dependence"]:
        q = draw_effect_params("rate_dependence", form, rng)
        sizes = []
        for u in slow_and_fast_triangles(peak, dt):
            base = BLIND2_CORES[plant](u, dt, params)
            temps, loads = np.full_like(u, 22.0), np.zeros_like(u)
            on = render(BLIND2_CORES[plant], params, u, dt, form, q, loads, temps, base)
            sizes.append(float(np.sqrt(np.mean((on - base) ** 2))))
        assert sizes[1] > 3.0 * sizes[0], (form, sizes)


@pytest.mark.parametrize("core", list(BLIND2_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    assert_closed_loop_3_to_20_percent_wide(
        BLIND2_CORES[core], partial(draw_params, core), cycles=3, settled_share=0.01
    )


@pytest.mark.parametrize("protocol", list(BLIND2_PROTOCOLS))
def test_protocols_start_vented_stay_in_range_and_excite(protocol: str) -> None:
    dt, peak = 1.0 / 70.0, 4.0
    u = with_range_check(protocol, 60.0, dt, peak, np.random.default_rng(2))
    assert u.size == 4200 and np.all(np.isfinite(u)) and np.all(u[:70] == 0.0)
    assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:420]) >= 0.97 * peak
    assert np.ptp(u[420:]) > 0.4 * peak
