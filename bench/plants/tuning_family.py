"""The tuning family as a spec: the Bouc-Wen, generalised-play and friction-spring plants and the
HIL (:mod:`bench.plants.family`), every effect in both forms of :mod:`bench.plants.effects`.

Its records come from its own recorder (the HIL through ``hil.record``, the cores through
:func:`bench.plants.effects.apply`), not from the engine's template: it keeps no effect-free
twin of a record, so the contract checks that need one are tagged off.
"""

from __future__ import annotations

from bench.plants import cores, effects, family
from bench.plants.engine import FamilySpec
from bench.plants.protocols import PROTOCOLS, with_conditioning

SPEC = FamilySpec(
    name="tuning",
    cores=cores.CORES,
    forms=effects.FORMS,
    protocols=tuple(PROTOCOLS),
    rates_hz=family.RATES_HZ,
    noise_mm=dict.fromkeys(cores.CORES, family.NOISE_MM),
    seed_base=100,
    rotate=lambda i, p: (i, i // 4 + i),
    excite=lambda protocol, duration_s, dt, peak, rng: with_conditioning(protocol, duration_s, dt, peak, rng),
    draw_params=cores.draw_params,
    none_per_plant=family.NONE_PER_PLANT,
    # its second group of plants is numbered from zero again (seeds repeat) and the HIL has one form
    tags=frozenset({"check_cases_cover_the_spec"}),
    custom_cases=family.tuning_cases,
    custom_record=family.measurement,
)
