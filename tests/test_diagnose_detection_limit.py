"""The detection limit a ``none`` verdict states: the smallest effect the record could have named.

The formula is checked against the rule it inverts; end to end, load effects of growing size are
named when the part of them the baseline cannot absorb clears the limit their record states,
and not when it stays below.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from edge.hysteresis.pi import play_outputs
from host.data import Measurement
from host.diagnose.decide import COLUMN_GAIN_FLOOR, GAIN_FLOOR, NOISE_SHARE, detection_limit
from host.diagnose.run import diagnose


@pytest.mark.parametrize("floor", [GAIN_FLOOR, COLUMN_GAIN_FLOOR])
@pytest.mark.parametrize("base", [0.05, 1.0, 30.0])
def test_an_effect_at_the_limit_gains_exactly_the_floor(floor, base):
    # the effect is inside the baseline's error B: explaining its part e leaves sqrt(B^2 - e^2)
    e = detection_limit(base, noise=0.0, floor=floor)
    assert 1.0 - np.sqrt(base**2 - e**2) / base == pytest.approx(floor)
    assert 1.0 - np.sqrt(base**2 - (0.99 * e) ** 2) / base < floor


def test_near_the_noise_floor_the_noise_rule_sets_the_limit():
    # explaining the part e must also lower the error by a quarter of the noise
    base, noise = 1.0, 3.0
    e = detection_limit(base, noise=noise, floor=COLUMN_GAIN_FLOOR)
    assert base - np.sqrt(base**2 - e**2) == pytest.approx(NOISE_SHARE * noise)
    assert detection_limit(0.5, noise=3.0, floor=GAIN_FLOOR) == np.inf  # nothing can beat that noise


def _record(load_effect_rms: float) -> Measurement:
    """A play hysteresis driven by a sine of two speeds; a hanging mass changed at random times
    (steps unrelated to the input and to time) moves the output by ``load_effect_rms`` RMS."""
    rng = np.random.default_rng(5)
    dt = 0.02
    t = np.arange(int(120 / dt), dtype=np.float64) * dt
    u = 2.5 + 2.0 * np.sin(2 * np.pi * 0.07 * t) * (0.6 + 0.4 * np.sin(2 * np.pi * 0.011 * t))
    y = 8.0 * play_outputs(u, np.array([0.12, 0.4]), np.array([u[0], u[0]])).sum(axis=1)
    changes = np.sort(rng.uniform(0, t[-1], 14))
    load = 1.0 + rng.uniform(0.0, 2.0, changes.size + 1)[np.searchsorted(changes, t)]
    centred = load - load.mean()
    y = y + load_effect_rms * centred / np.sqrt(np.mean(centred**2)) + rng.normal(0.0, 0.02, t.size)
    extras = {"load": np.round(load + rng.normal(0, 0.005, t.size), 3), "temperature": 22 + 0.5 * np.sin(t / 17)}
    return Measurement(t, u, y, extras, source="limit")


def _diagnosed(load_effect_rms: float):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(_record(load_effect_rms), progress=False)


def test_an_effect_whose_own_part_clears_the_stated_limit_is_named_and_one_below_it_is_not():
    # each record states its own limit from its own baseline error B (any effect included); the
    # effect's own part is what it adds to the effect-free record's error B0 (the flexible
    # Preisach model absorbs much of a slowly stepping load). Scaled 1-8x the effect-free limit,
    # each injected load effect is named when its own part is clearly above its record's limit
    # and not when clearly below (both happen); the load term gains no more than the arithmetic
    # allows, 1 - B0 / B, and most of it (its held-out refit costs a little).
    clean = _diagnosed(0.0)
    assert clean.cause == "none"
    limit = clean.confidence["detection_limit"]
    assert 0 < limit["measured_column"] < limit["dynamic_term"]
    assert f"{limit['dynamic_term']:.3g} RMS" in clean.reason and "smaller effects may be present" in clean.reason
    b0, seen = limit["baseline_rmse"], set()
    for scale in (1.0, 2.0, 4.0, 8.0):
        d = _diagnosed(scale * limit["measured_column"])
        stated = d.confidence["detection_limit"]
        own = np.sqrt(stated["baseline_rmse"] ** 2 - b0**2)
        ideal = 1.0 - b0 / stated["baseline_rmse"]  # a term that explains exactly the own part
        assert 0.6 * ideal - 0.02 <= d.scores["load_dependence"] <= ideal + 0.03, (scale, ideal, d.scores)
        if own >= 1.2 * stated["measured_column"]:
            assert d.cause == "load_dependence", (scale, own, d.reason)
            seen.add("above")
        elif own <= 0.8 * stated["measured_column"]:
            assert d.cause == "none", (scale, own, d.reason)
            seen.add("below")
    assert seen == {"above", "below"}


def test_a_record_without_a_moving_column_states_no_column_limit():
    m = _record(0.0)
    m = Measurement(m.t, m.u, m.y, {}, source="no columns")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = diagnose(m, progress=False)
    assert d.cause == "none" and d.confidence["detection_limit"]["measured_column"] is None
    assert "through a load or temperature column" not in d.reason
