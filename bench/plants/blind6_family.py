"""An eighth, truly blind held-out plant family for ``pmactl diagnose`` (blind6).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind6_cores`): a pleated (Daerden) muscle with Berg's
  hyperbolic rubber friction; a Rayleigh-law braid (quadratic branches, wiping-out memory) on an
  exponential-force muscle solved with the Lambert W; a quadratic-force muscle whose carriage
  runs in a friction wedge (a Coulomb limit growing with the stroke, presliding); a braid with
  slip-lock *pinching* (generalised plays that collapse in a pressure band) on a logistic map.
* Five protocols (:mod:`bench.plants.blind6_protocols`): an EMG-proportional envelope,
  cardiac-assist pulses, a teleoperated joystick, creep-recovery blocks, a rate decade of
  triangles; each starts vented and does a choked-flow sweep (fill to the top and vent) in its
  first ~5 s.
* Every effect in two new forms (:mod:`bench.plants.blind6_effects`).
* Sample rates 66, 105, 168, 232, 345 and 490 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it
(:func:`bench.plants.blind5_family.calibrate`: up to three proportional passes, at most 3 x from
the drawn intensity either way, recorded in the truth as ``target_over_span`` and
``calibration``); then, as in every held-out family,
:func:`bench.plants.visibility.visible_effect` makes sure the size lies in ``[5 x noise, 12 %
of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind6_rig`): a second-order
spool valve (6-14 Hz, damping 0.55-0.8), the recorded input read through the transducer's
snubber (a 4-15 ms lag behind the muscle's pressure), compressor vibration bursts on the frame
(8-25 um at 23-31 Hz), the multiplexer's crosstalk of the pressure into the stroke channel
(10-40 um at full pressure), the DAQ's sampling jitter (20-100 us RMS) on every channel; stroke
noise 0.01-0.028 mm and a reading step of 0.005-0.025 mm per plant; load (read to 0.002 kg) and
temperature (read to 0.025 K) columns that always move and act only in their own effect's
records. The table of every case: ``python -m bench.plants.blind6_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind5_family import calibrate
from bench.plants.blind6_cores import BLIND6_CORES, draw_params
from bench.plants.blind6_effects import BLIND6_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind6_protocols import BLIND6_PROTOCOLS, with_choked_sweep
from bench.plants.blind6_rig import aperture_jitter, snubbed_reading
from bench.plants.family import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
BLIND6_PLANTS = tuple(BLIND6_CORES)
BLIND6_RATES_HZ = (66.0, 232.0, 490.0, 105.0, 345.0, 168.0)
NOISE_MM = {
    "pleated_berg": 0.016,
    "rayleigh_lambert": 0.022,
    "wedge_damper": 0.028,
    "pinched_sliplock": 0.01,
}
QUANT_MM = {
    "pleated_berg": 0.005,
    "rayleigh_lambert": 0.015,
    "wedge_damper": 0.025,
    "pinched_sliplock": 0.005,
}
LOAD_READ_KG, LOAD_NOISE_KG = 0.002, 0.004
TEMP_READ_K, TEMP_NOISE_K = 0.025, 0.03
NONE_PER_PLANT = 5
SEED_BASE = 33000
SEED_OFFSET = 130_000  # measurement noise seeded at case.seed + 130_000, independent of the plant draws
SENSORS = {
    p: Sensors(SEED_OFFSET, QUANT_MM[p], LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K) for p in NOISE_MM
}
TARGET_OVER_SPAN = (0.01, 0.1)
TARGET_MIN_OVER_NOISE = 6.0
LOAD_TEMP_EFFECTS = ("load_dependence", "temperature_drift")


def blind6_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every blind6 core plus :data:`NONE_PER_PLANT` effect-free records
    each (60 records); protocols (5) and rates (6) rotate so every pair occurs, and every form
    meets several protocols and rates."""
    out: list[Case] = []
    protocols, n_rates = list(BLIND6_PROTOCOLS), len(BLIND6_RATES_HZ)
    i = 0
    for p_index, plant in enumerate(BLIND6_PLANTS):
        for effect, forms in BLIND6_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    protocol = protocols[(i + 2 * p_index) % len(protocols)]
                    rate = BLIND6_RATES_HZ[(i + p_index) % n_rates]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the recorded input (the muscle's pressure
    through the transducer's snubber, from the set pressure ``command`` [bar] the valve got),
    the columns and the truth."""
    if case.plant not in BLIND6_CORES:
        raise KeyError(f"unknown blind6 plant {case.plant!r}; known: {', '.join(BLIND6_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 6.0))  # bar
    u = with_choked_sweep(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    core = BLIND6_CORES[case.plant]
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
    sim = {"t": t, "u": snubbed_reading(u, dt, params), "command": u, "on": on, "off": off}
    return {**sim, "load": load, "temperature": temperature, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result (:data:`SENSORS` of its plant),
    every channel sampled with the DAQ's aperture jitter (time stamps nominal)."""
    dt = 1.0 / case.rate_hz
    jitter_rng = np.random.default_rng(case.seed + SEED_OFFSET + 1)
    jitter = jitter_rng.normal(0.0, sim["truth"]["plant_parameters"]["jitter_s"], sim["on"].size)
    jittered = {**sim, "on": aperture_jitter(sim["on"], dt, jitter), "u": aperture_jitter(sim["u"], dt, jitter)}
    for name in ("load", "temperature"):
        jittered[name] = aperture_jitter(sim[name], dt, jitter)
    m, truth = recorded(case, jittered, SENSORS[case.plant])
    truth["jitter_s"] = float(np.std(jitter))
    return m, truth


def blind6_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    return case_table(blind6_cases(duration_s), simulate, duration_s)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
