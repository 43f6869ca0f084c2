"""The plant corpus the diagnosis is scored on: thirteen families of synthetic muscle plants.

Each family is its own physics (``<name>_cores``, ``<name>_effects``, ``<name>_protocols`` and,
for most, ``<name>_rig``) and one spec, ``SPEC`` in ``<name>_family.py``
(:class:`bench.plants.engine.FamilySpec`); :mod:`bench.plants.engine` lists, simulates and
records the cases of any spec, :mod:`bench.plants.registry` finds the specs by scanning, and
:mod:`bench.plants.contract` holds the promises every family keeps. A new family is its physics
modules plus a spec here; ``tests/test_plant_contract.py`` checks it with no new test module.
Nothing under ``edge/`` or ``host/`` imports this package, and it knows nothing of the diagnosis.
"""
