"""Hardware-in-the-loop emulator of a pneumatic-muscle rig.

``hil.plant``: muscle + valve + load physics as pure functions. ``hil.effects``: the switchable
effects (rate dependence, creep, transport delay, load dependence, temperature drift).
``hil.scenarios``: test protocols after the seed papers. ``hil.record``: measured-data CSVs with
a truth sidecar. ``hil.devices``: register-level chip emulators behind the edge's bus ports.
"""
