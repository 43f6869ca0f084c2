"""A family of test plants for ``pmactl diagnose`` that is wider than the HIL.

Three hysteresis cores that share nothing with the HIL or with the diagnosis's own Preisach
baseline (:mod:`bench.plants.cores`), four protocols (:mod:`bench.plants.protocols`), every
effect in two functional forms (:mod:`bench.plants.effects`), and the HIL itself through
``hil.record``. :mod:`bench.plants.family` builds a recording for a case and splits the cases
into a tuning set and a held-out set, fixed before any tuning.
"""
