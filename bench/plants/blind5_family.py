"""A seventh, truly blind held-out plant family for ``pmactl diagnose`` (blind5).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind5_cores`): a vector play of crossed braid fibres on the
  curved (axial, hoop) path of a Chou-Hannaford muscle; a rolling lobe with peel and
  re-adhesion thresholds; a frictionless muscle read through a draw-wire sensor with stick-slip;
  a moving Prandtl-Ishlinskii braid with a negative-stiffness assist spring and lock-up.
* Five protocols (:mod:`bench.plants.blind5_protocols`): an equal-step pressure ladder with
  holds of 2-10 s, minor loops riding on a major triangle, pedal assist with wandering cadence,
  pick-and-place gripper cycles, blocks of trapezoids with dwells; each starts vented and does a
  valve sweep (first-order fill to the top and vent) in its first ~5 s.
* Every effect in two new forms (:mod:`bench.plants.blind5_effects`).
* Sample rates 84, 135, 192, 256, 375 and 440 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it (up to
three proportional passes, at most 3 x from the drawn intensity either way so that it stays
plausible, recorded in the truth as ``target_over_span`` and ``calibration``); then, as in
every held-out family, :func:`bench.plants.visibility.visible_effect` makes sure the size lies
in ``[5 x noise, 12 % of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind5_rig`): the supply
regulator's lag (25-70 ms) and its diaphragm's play (0.4-1.2 % of the peak), a pressure
transducer gain error (0.6-2 %) and offset in the recorded input, the mount settling
0.015-0.04 mm over 15-40 s, aliased mains hum of 4-12 um, 0.1-0.4 % dropped DAQ frames repeated on
every channel; stroke noise 0.012-0.03 mm and a reading step of 0.01-0.03 mm per plant; load
(read to 0.01 kg) and temperature (read to 0.02 K) columns that always move and act only in
their own effect's records. The table of every case: ``python -m bench.plants.blind5_family 100``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind5_cores import BLIND5_CORES, draw_params
from bench.plants.blind5_effects import BLIND5_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind5_protocols import BLIND5_PROTOCOLS, with_valve_sweep
from bench.plants.blind5_rig import dropped_frames, transducer_reading
from bench.plants.family import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import rms, visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
BLIND5_PLANTS = tuple(BLIND5_CORES)
BLIND5_RATES_HZ = (84.0, 192.0, 375.0, 135.0, 440.0, 256.0)
NOISE_MM = {
    "vector_fibre_play": 0.02,
    "rolling_lobe_peel": 0.028,
    "drawwire_stickslip": 0.012,
    "moving_play_assist": 0.03,
}
QUANT_MM = {
    "vector_fibre_play": 0.01,
    "rolling_lobe_peel": 0.02,
    "drawwire_stickslip": 0.01,
    "moving_play_assist": 0.03,
}
LOAD_READ_KG, LOAD_NOISE_KG = 0.01, 0.006
TEMP_READ_K, TEMP_NOISE_K = 0.02, 0.02
NONE_PER_PLANT = 5
SEED_BASE = 27000
SEED_OFFSET = 110_000  # measurement noise seeded at case.seed + 110_000, independent of the plant draws
SENSORS = {
    p: Sensors(SEED_OFFSET, QUANT_MM[p], LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K) for p in NOISE_MM
}
TARGET_OVER_SPAN = (0.01, 0.1)
TARGET_MIN_OVER_NOISE = 6.0
MAX_CALIBRATION = 3.0  # the drawn intensity is moved at most 3 x either way, to stay plausible
LOAD_TEMP_EFFECTS = ("load_dependence", "temperature_drift")


def blind5_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every blind5 core plus :data:`NONE_PER_PLANT` effect-free records
    each (60 records); protocols (5) and rates (6) rotate so every pair occurs, and every form
    meets four protocols and several rates."""
    out: list[Case] = []
    protocols, n_rates = list(BLIND5_PROTOCOLS), len(BLIND5_RATES_HZ)
    i = 0
    for p_index, plant in enumerate(BLIND5_PLANTS):
        for effect, forms in BLIND5_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    protocol = protocols[(i + p_index) % len(protocols)]
                    rate = BLIND5_RATES_HZ[(i + 2 * p_index) % n_rates]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def calibrate(render_on: Callable[[], Array], off: Array, q: dict[str, float], key: str, target: float) -> None:
    """Scale ``q[key]`` so that the effect's size (RMS [mm] of ``render_on() - off``) comes near
    ``target`` [mm]: up to three proportional passes, in all at most :data:`MAX_CALIBRATION` x
    either way (the size the drawn intensity gives is kept where the target is farther)."""
    factor = 1.0
    for _ in range(3):
        size = rms(render_on() - off)
        if size <= 0.0:
            break
        step = float(np.clip(target / size, 1.0 / MAX_CALIBRATION / factor, MAX_CALIBRATION / factor))
        if abs(step - 1.0) < 0.05:
            break
        q[key] *= step
        factor *= step
    q["calibration"] = factor


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the recorded input (the transducer's
    reading of the set pressure ``command`` [bar] the plant got), the columns and the truth."""
    if case.plant not in BLIND5_CORES:
        raise KeyError(f"unknown blind5 plant {case.plant!r}; known: {', '.join(BLIND5_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 6.0))  # bar
    u = with_valve_sweep(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    core = BLIND5_CORES[case.plant]
    params = draw_params(case.plant, rng, peak)
    load, temperature, load_pattern, temp_pattern = columns(t, rng)
    q = draw_effect_params(case.effect, case.form, rng)
    share = float(np.exp(rng.uniform(*np.log(TARGET_OVER_SPAN))))
    noise = NOISE_MM[case.plant]
    base = core(u, dt, params)
    if case.effect in LOAD_TEMP_EFFECTS:  # the same plant with its column held still
        held_load, held_temp = np.full_like(load, load[0]), np.full_like(temperature, temperature[0])
        off = render(core, params, u, dt, case.form, q, held_load, held_temp, base)
    else:
        off = render(core, params, u, dt, "none", q, load, temperature, base)

    memo: dict[float, Array] = {}

    def with_effect() -> Array:
        key_value = q.get(INTENSITY_KEY.get(case.form, ""), 0.0)
        if key_value not in memo:
            memo.clear()
            memo[key_value] = render(core, params, u, dt, case.form, q, load, temperature, base)
        return memo[key_value]

    key, patterns = INTENSITY_KEY.get(case.form, ""), (load_pattern, temp_pattern)  # no key: effect-free
    if case.effect != "none":
        target = max(share * float(np.ptp(off)), TARGET_MIN_OVER_NOISE * noise)
        q["target_over_span"] = target / float(np.ptp(off))
        calibrate(with_effect, off, q, key, target)
    on, truth = visible_effect(case.effect, case.form, with_effect, off, noise, q, key, 1.3, params, patterns)
    u_read = transducer_reading(u, params)
    sim = {"t": t, "u": u_read, "command": u, "on": on, "off": off, "load": load, "temperature": temperature}
    return {**sim, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result (:data:`SENSORS` of its plant),
    with the frames the DAQ dropped repeating the frame before on every channel."""
    m, truth = recorded(case, sim, SENSORS[case.plant])
    drops = dropped_frames(
        len(m), np.random.default_rng(case.seed + SEED_OFFSET + 1), sim["truth"]["plant_parameters"]["drop_share"]
    )
    y, u = m.y.copy(), m.u.copy()
    extras = {name: column.copy() for name, column in m.extras.items()}
    for i in drops.tolist():  # in order, so a run of drops repeats the last good frame
        y[i], u[i] = y[i - 1], u[i - 1]
        for column in extras.values():
            column[i] = column[i - 1]
    truth["dropped_frames"] = int(drops.size)
    return Measurement(m.t, u, y, extras, source=m.source), truth


def blind5_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    return case_table(blind5_cases(duration_s), simulate, duration_s)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
