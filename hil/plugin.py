"""The ``sim`` backend of the edge runtime (entry point ``pmactl.backends``).

``sim://rig?adc=ADS1015&effect=none&seed=0&clock=lockstep`` builds a :class:`~hil.rig.HilRig`
with its emulated chips on the config's I2C clock rate. ``clock=lockstep`` (default) runs on a
simulated clock, ``clock=realtime`` on the wall clock.
"""

from __future__ import annotations

from urllib.parse import parse_qs, urlsplit

import numpy as np

from edge.errors import ConfigError
from edge.hal.clock import MonotonicClock
from edge.runtime.config import RigConfig
from hil.effects import EFFECTS, apply_effect
from hil.plant import PlantParams
from hil.rig import HilRig

OPTIONS = {"adc", "effect", "seed", "clock"}


class SimRig:
    """A HilRig exposed as the plug-in protocol of ``edge.runtime.backends``."""

    def __init__(self, rig: HilRig, lockstep: bool, truth: dict[str, object]) -> None:
        self.rig, self.lockstep, self.truth = rig, lockstep, truth
        self.bus, self.gpio, self.clock = rig.bus, rig.gpio, rig.clock


def open_sim(url: str, config: RigConfig) -> SimRig:
    query = {k: v[-1] for k, v in parse_qs(urlsplit(url).query).items()}
    unknown = set(query) - OPTIONS
    if unknown:
        raise ConfigError(f"{config.source}: sim:// option(s) {sorted(unknown)} unknown; use {sorted(OPTIONS)}")
    adc = query.get("adc", config.adc.chip)
    if adc != config.adc.chip:
        raise ConfigError(
            f"{config.source}: sim:// emulates an {adc} but [adc] chip is {config.adc.chip}; make them agree"
        )
    effect = query.get("effect", "none")
    if effect not in EFFECTS:
        raise ConfigError(f"{config.source}: sim:// effect {effect!r} unknown; use one of {list(EFFECTS)}")
    clock_mode = query.get("clock", "lockstep")
    if clock_mode not in ("lockstep", "realtime"):
        raise ConfigError(f"{config.source}: sim:// clock={clock_mode!r}; use lockstep or realtime")
    seed = int(query.get("seed", "0"))
    params, truth = apply_effect(effect, PlantParams(), np.random.default_rng(seed), 3600.0)
    clock = MonotonicClock() if clock_mode == "realtime" else None
    rig = HilRig(params, clock=clock, seed=seed, adc_variant=adc, bus_hz=config.rig.i2c_bus_hz)
    return SimRig(rig, clock_mode == "lockstep", truth)
