"""A twelfth, truly blind held-out plant family for ``pmactl diagnose`` (blind10).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind10_cores`), each on a Chou-Hannaford braid around a Gent
  bladder: Haessig-Friedland bristles between bladder and braid (bonds that snap and re-bond at
  random: a friction whose loops never repeat exactly); the braid's crossings as an
  Olami-Feder-Christensen lattice (slip avalanches of all sizes); twin muscles in parallel, the
  second fed through opposed check valves (an asymmetric play of the pressure from the pneumatic
  circuit); a snap-action over-centre spring on the carriage (one macroscopic snap each way) with
  a little Coulomb friction.
* Five protocols (:mod:`bench.plants.blind10_protocols`): a frequency-hopping sine, a
  crank-driven bellows, a bias ladder with a sine on every rung, the Lorenz system's chaos, a
  pneumatic relaxation oscillator; each starts vented and is shaken down by three sawtooth fills
  with quick exhausts in its first ~6 s.
* Every effect in two forms (:mod:`bench.plants.blind10_effects`): a plain textbook one in a new
  parameterisation (a linear dashpot held by the muscle's stiffness, first-order creep driven by
  the pressure, a pure dead time in the supply line, a linear compliance in the load path, a
  linear temperature coefficient of the gain) and an unusual one (the bladder's self-heating,
  Struik ageing creep, a PLC whose scan time grows with its workload, a rope's knots bedding in, an
  R-phase NiTi bias spring with thermal hysteresis).
* Sample rates 52, 128, 184, 264, 352 and 464 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it
(:func:`bench.plants.blind5_family.calibrate`: up to three proportional passes, at most 3 x from
the drawn intensity either way, recorded in the truth as ``target_over_span`` and
``calibration``); then, as in every held-out family, :func:`bench.plants.visibility.visible_effect`
makes sure the size lies in ``[5 x noise, 12 % of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind10_rig`): an I/P
converter (15-35 ms) piloting a volume booster that exhausts faster than it fills (25-60 ms,
0.35-0.7 x on the way down); the recorded input from a 4-20 mA transmitter at the booster's
outlet that updates every 8-20 ms, with HART FSK bursts on its loop (aliased through the RC
anti-alias filter), read with 1.5-4 mbar of noise and a 12-bit step; a magnetostrictive stroke
sensor with a periodic nonlinearity (4-12 um), a bow (5-15 um) and triboelectric cable noise that
grows with the speed (3-8 um at 20 mm/s); stroke noise 0.012-0.03 mm and a reading step of
1-5 um per plant; a load column from a 24-bit bridge converter at 10 or 80 conversions per second
(held: stairs) and a temperature column from an NTC probe (1-4 s bead lag) through a 10-bit
divider (a non-uniform step). The load and temperature columns always move and act only in
their own effect's records (one temperature pattern follows the load's activity: a decoy
correlated with the load). The table of every case: ``python -m bench.plants.blind10_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind5_family import calibrate
from bench.plants.blind10_cores import BLIND10_CORES, draw_params
from bench.plants.blind10_effects import BLIND10_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind10_protocols import BLIND10_PROTOCOLS, with_exhaust_shakedown
from bench.plants.blind10_rig import hx711_load, ntc_temperature, pressure_reading, recorded_pressure
from bench.plants.family import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
BLIND10_PLANTS = tuple(BLIND10_CORES)
BLIND10_RATES_HZ = (52.0, 184.0, 464.0, 128.0, 352.0, 264.0)
NOISE_MM = {
    "bristle_bladder": 0.016,
    "avalanche_crossings": 0.024,
    "check_valve_twin": 0.012,
    "overcentre_latch": 0.03,
}
QUANT_MM = {
    "bristle_bladder": 0.002,
    "avalanche_crossings": 0.001,
    "check_valve_twin": 0.005,
    "overcentre_latch": 0.002,
}
TEMP_READ_K = 1e-6  # the NTC's counts make the real (non-uniform) step; this only rounds floats
NONE_PER_PLANT = 5
SEED_BASE = 47000
SEED_OFFSET = 290_000  # measurement noise seeded at case.seed + 290_000, independent of the plant draws
LOAD_STEP_KG = 0.0005  # the bridge converter's count, as scaled
SENSORS = {p: Sensors(SEED_OFFSET, QUANT_MM[p], 0.0, LOAD_STEP_KG, 0.0, TEMP_READ_K) for p in NOISE_MM}
TARGET_OVER_SPAN = (0.01, 0.1)
TARGET_MIN_OVER_NOISE = 6.0
LOAD_TEMP_EFFECTS = ("load_dependence", "temperature_drift")


def blind10_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every blind10 core plus :data:`NONE_PER_PLANT` effect-free records
    each (60 records); protocols (5) and rates (6) rotate so every pair occurs, and every form
    meets several protocols and rates."""
    out: list[Case] = []
    protocols, n_rates = list(BLIND10_PROTOCOLS), len(BLIND10_RATES_HZ)
    i = 0
    for p_index, plant in enumerate(BLIND10_PLANTS):
        for effect, forms in BLIND10_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    protocol = protocols[(i + 3 * p_index) % len(protocols)]
                    rate = BLIND10_RATES_HZ[(i + 2 * p_index) % n_rates]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the recorded input (the transmitter's
    channel, noise-free: :func:`measurement_from` adds the converter's noise and step), the set
    pressure ``command`` [bar] the I/P converter got, the true columns and the truth."""
    if case.plant not in BLIND10_CORES:
        raise KeyError(f"unknown blind10 plant {case.plant!r}; known: {', '.join(BLIND10_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 6.0))  # bar
    u = with_exhaust_shakedown(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    params = draw_params(case.plant, rng, peak)
    load, temperature, load_pattern, temp_pattern = columns(t, rng)
    q = draw_effect_params(case.effect, case.form, rng)
    share = float(np.exp(rng.uniform(*np.log(TARGET_OVER_SPAN))))
    noise = NOISE_MM[case.plant]
    base = BLIND10_CORES[case.plant](u, dt, params)
    if case.effect in LOAD_TEMP_EFFECTS:  # the same plant with its column held still
        held_load, held_temp = np.full_like(load, load[0]), np.full_like(temperature, temperature[0])
        off = render(case.plant, params, u, dt, case.form, q, held_load, held_temp, base)
    else:
        off = render(case.plant, params, u, dt, "none", q, load, temperature, base)

    memo: dict[float, Array] = {}

    def with_effect() -> Array:
        key_value = q.get(INTENSITY_KEY.get(case.form, ""), 0.0)
        if key_value not in memo:
            memo.clear()
            memo[key_value] = render(case.plant, params, u, dt, case.form, q, load, temperature, base)
        return memo[key_value]

    key, patterns = INTENSITY_KEY.get(case.form, ""), (load_pattern, temp_pattern)  # no key: effect-free
    if case.effect != "none":
        target = max(share * float(np.ptp(off)), TARGET_MIN_OVER_NOISE * noise)
        q["target_over_span"] = target / float(np.ptp(off))
        calibrate(with_effect, off, q, key, target)
    on, truth = visible_effect(case.effect, case.form, with_effect, off, noise, q, key, 1.3, params, patterns)
    sim = {"t": t, "u": recorded_pressure(u, dt, params), "command": u, "on": on, "off": off, "base": base}
    return {**sim, "load": load, "temperature": temperature, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result (:data:`SENSORS` of its plant;
    the input read by the transmitter's converter, the load by the bridge converter, held between
    conversions, the temperature by the NTC probe and its 10-bit divider)."""
    params = sim["truth"]["plant_parameters"]
    dt = 1.0 / case.rate_hz
    read_input = pressure_reading(sim["u"], params, np.random.default_rng(case.seed + SEED_OFFSET + 1))
    read_load = hx711_load(sim["load"], dt, params, np.random.default_rng(case.seed + SEED_OFFSET + 2))
    read_temp = ntc_temperature(sim["temperature"], dt, params, np.random.default_rng(case.seed + SEED_OFFSET + 3))
    return recorded(case, {**sim, "u": read_input, "load": read_load, "temperature": read_temp}, SENSORS[case.plant])


def blind10_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    return case_table(blind10_cases(duration_s), simulate, duration_s)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
