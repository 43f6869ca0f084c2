"""The actuator before the hysteresis (:mod:`host.diagnose.actuator`).

When the recorded input is the valve command, the muscle's pressure follows it through the
valve and the chamber, a lag *before* the hysteresis. An output lag cannot stand in for it (a
lag before a hysteresis widens the loop with the input's speed), so without the actuator an
effect-free campaign was named ``rate_dependence``. The actuator lag is chosen per record,
under the alternative (with every cause's terms), before any cause is tested.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from host.data import Measurement
from host.diagnose.actuator import driven, usable_lags
from host.diagnose.nuisance import lowpass
from host.diagnose.rules import RULES
from host.diagnose.runs import run_set
from host.diagnose.v3 import diagnose_runs
from tests.test_diagnose_v3 import RATE_HZ, noisy, pi_core, rested_cycle

SEEDS = (3, 4, 5, 6, 7, 8)


def valve_runs(seed: int, valve_s: float, n_runs: int = 12) -> list[Measurement]:
    """Effect-free runs whose input [bar] is the valve command: the muscle's pressure follows it
    through a first-order lag of ``valve_s`` [s], then the hysteresis, then a 50 ms output lag."""
    rng = np.random.default_rng(seed)
    runs = []
    for i in range(n_runs):
        t, u = rested_cycle(seed + i, rng, seconds=(2.0, 7.0))
        x = pi_core(lowpass(u, 1 / RATE_HZ, valve_s), seed)
        runs.append(Measurement(t, u, noisy(lowpass(x, 1 / RATE_HZ, 0.05), rng), {}, f"run{i:02d}.csv"))
    return runs


def test_an_inverse_lag_undoes_the_lag_run_by_run():
    runs = valve_runs(3, 0.0, n_runs=3)
    rs = run_set(runs, RULES.max_rows, RULES.min_samples)
    lagged = dataclasses.replace(rs, u=np.concatenate([lowpass(m.u, 1 / RATE_HZ, 0.025) for m in runs]))
    assert np.allclose(driven(lagged, -0.025).u, rs.u, atol=1e-9)
    assert driven(rs, 0.0) is rs
    signed = dataclasses.replace(RULES, input_lags_s=(-0.025, -0.001, 0.001, 0.05))
    assert usable_lags(rs, signed) == [-0.025, 0.0, 0.05]  # 0 always; under half a sample either way dropped
    assert usable_lags(rs, dataclasses.replace(RULES, input_lags_s=(0.0,))) == [0.0]


def test_a_valve_lag_before_the_hysteresis_is_the_rig_not_a_rate_effect():
    with_actuator = [diagnose_runs(valve_runs(seed, 0.1)) for seed in SEEDS]
    assert sum(d.runset.input_lag_s == 0.1 for d in with_actuator) >= 5
    assert sum(d.cause == "none" for d in with_actuator) >= 5, [d.cause for d in with_actuator]
    assert any("actuator" in note for note in with_actuator[0].notes)
    without = dataclasses.replace(RULES, input_lags_s=(0.0,))
    named = [diagnose_runs(valve_runs(seed, 0.1), rules=without).cause for seed in SEEDS]
    assert named.count("rate_dependence") >= 4, named
