"""Every effect in two forms none of the other ten families uses, and the always-moving columns.

Each effect has one form acting *inside* the core (through the muscle's force balance or its
pressure: :data:`INSIDE_FORMS`, the core re-driven with ``mods``, see
:mod:`bench.plants.blind9_cores`) and one acting on the contraction or its reading after it.

Rate dependence: the bladder's rubber as a *Bergstrom-Boyce* network (a second network in
series with a power-law viscous flow whose rate grows as the ``m``-th power of its stress and
falls with its stretch: a nonlinear viscoelastic force that the muscle pulls against, inside);
the payload's mass on the muscle's *pressure-dependent stiffness* (a resonance whose frequency
rises with the pressure, after). Creep: *Doi-Edwards reptation* of the bladder's entangled
chains (its resistance relaxes with the reptation kernel ``sum_odd 8 / (pi^2 p^2) exp(-p^2 t /
tau_d)``, superposed over the pressure's history: more effective pressure, inside); the sleeve
creeping as a *fractional Kelvin-Voigt* element (the Mittag-Leffler creep ``1 - E_alpha(-(t /
tau)^alpha)`` superposed over the stroke's history, after). Transport delay: a *pneumatic line*
between the manifold (where the input is read) and the muscle (an acoustic dead time ``length /
c`` and a lag ``R C`` growing with the muscle's volume, i.e. its pressure: inside); the smart
string pot's *One-Euro filter* (a low-pass whose cut-off rises with the speed: much lag when
slow, little when fast; after). Load dependence: the payload's weight through the muscle's
*force-length map* via a lever (inside: a pressure- and stroke-dependent sensitivity, and the
hysteresis met at the shifted stroke); the *vented muscle elongating* under the payload (the
slack braid leaves the load to the bladder at low pressure: a stiffening, logarithmic stretch
that fades as the braid engages; after). Temperature drift: the bladder's *modulus softening*
(a filled rubber's modulus falling 1-3 %/K: less pressure spent inflating it onto the braid and
less hoop resistance, through the bladder's thermal lag, inside); the
bladder and its fittings' *thermal elongation* (rest length growing ``alpha L0 dT``, partly
taken up by the braid as the pressure rises, through a thermal lag, after).

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Load: a cart on a ramp a screw jack tilts, or an electromagnet under the payload pulling
with current steps (each rising with its ``L / R``). Temperature: a thermocouple on the sleeve
warming at every fill and cooling at every vent (adiabatic compression) and warming slowly while
the muscle works (the rubber's hysteretic heating): a decoy following the input; or the supply
air warming while the compressor runs.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from bench.plants.blind9_cores import BLIND9_DRIVES, normalised_pressure
from bench.plants.blind9_rig import stroke_reading
from bench.plants.filters import lowpass, variable_delay

Array = NDArray[np.float64]
BLIND9_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("bergstrom_boyce_bladder", "pressure_stiffened_payload"),
    "creep": ("doi_edwards_reptation", "mittag_leffler_sleeve"),
    "transport_delay": ("acoustic_line_lag", "one_euro_filter"),
    "load_dependence": ("force_length_map", "vented_elongation"),
    "temperature_drift": ("bladder_modulus_softening", "thermal_elongation"),
}
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "bergstrom_boyce_bladder": "network_share",
    "pressure_stiffened_payload": "mass_s2",
    "doi_edwards_reptation": "reptation_share",
    "mittag_leffler_sleeve": "ml_share",
    "acoustic_line_lag": "line_m",
    "one_euro_filter": "min_tau_s",
    "force_length_map": "lever_ratio",
    "vented_elongation": "elong_mm",
    "bladder_modulus_softening": "softening_per_k",
    "thermal_elongation": "expansion_per_k",
}
INSIDE_FORMS: tuple[str, ...] = (  # the forms that re-drive the core (the rest act after it)
    "bergstrom_boyce_bladder",
    "doi_edwards_reptation",
    "acoustic_line_lag",
    "force_length_map",
    "bladder_modulus_softening",
)
G_MS2 = 9.81
SOUND_M_S = 343.0
REPTATION_MODES = 25  # odd modes 1, 3, .., 49


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------


def load_incline_cart(t: Array, rng: np.random.Generator) -> Array:
    """A 2-6 kg cart on a ramp whose angle a screw jack moves between 8 and 35 deg at 2-5 deg/s
    (a new angle at least 8 deg away), pausing 3-10 s; the first move within 3 s; the load is
    ``m sin(angle)``."""
    mass = float(rng.uniform(2.0, 6.0))
    knots_t, knots_a = [0.0, float(rng.uniform(0.0, 3.0))], [float(rng.uniform(8.0, 35.0))] * 2
    while knots_t[-1] < t[-1]:
        now = knots_a[-1]
        choices = [a for a in (8.0, 35.0) if abs(a - now) >= 8.0]
        target = float(rng.uniform(8.0, 35.0))
        if abs(target - now) < 8.0:
            target = float(rng.choice(choices))
        speed = float(rng.uniform(2.0, 5.0))
        knots_t += [knots_t[-1] + abs(target - now) / speed, 0.0]
        knots_t[-1] = knots_t[-2] + float(rng.uniform(3.0, 10.0))
        knots_a += [target, target]
    angle = np.radians(np.interp(t, knots_t, knots_a))
    return np.asarray(mass * np.sin(angle), dtype=np.float64)


def load_electromagnet_steps(t: Array, rng: np.random.Generator) -> Array:
    """A 1-3 kg pan and an electromagnet under it pulling ``P (i / I)^2`` (``P`` 1-2 kg at full
    current): the current alternates between a low (0 or 1/3) and a high (2/3 or full) level every
    5-15 s (first within 3 s), rising with the coil's ``L / R`` of 0.1-0.4 s."""
    dt = float(t[1] - t[0])
    pan, pull = float(rng.uniform(1.0, 3.0)), float(rng.uniform(1.0, 2.0))
    current = np.zeros_like(t)
    now, high = float(rng.uniform(0.0, 3.0)), True
    while now < t[-1]:
        level = float(rng.choice([2.0 / 3.0, 1.0])) if high else float(rng.choice([0.0, 1.0 / 3.0]))
        current[t >= now] = level
        high = not high
        now += float(rng.uniform(5.0, 15.0))
    current = lowpass(current, dt, float(rng.uniform(0.1, 0.4)))
    return np.asarray(pan + pull * current**2, dtype=np.float64)


def temp_compression_thermocouple(t: Array, rng: np.random.Generator, v: Array) -> Array:
    """A 20-25 degC room drifting by 0.5-1.5 K over 200-500 s, and a thermocouple on the sleeve
    of the muscle whose pressure is ``v`` [share of peak]: warming by ``k`` (1.5-4 K per full fill)
    at every fill and cooling at every vent, the heat leaving in 3-10 s (``k (v - lag(v))``), and
    the rubber's hysteretic self-heating, ``h`` (0.05-0.15 K per full-range travel) of every
    pressure change, shed with a time constant of 30-80 s."""
    dt = float(t[1] - t[0])
    room = float(rng.uniform(20.0, 25.0)) + float(rng.uniform(0.5, 1.5)) * np.sin(
        2.0 * np.pi * t / float(rng.uniform(200.0, 500.0)) + float(rng.uniform(0.0, 6.3))
    )
    k, tau = float(rng.uniform(1.5, 4.0)), float(rng.uniform(3.0, 10.0))
    h, shed = float(rng.uniform(0.05, 0.15)), float(rng.uniform(30.0, 80.0))
    keep = math.exp(-dt / shed)
    heating = lfilter([h], [1.0, -keep], np.abs(np.diff(v, prepend=v[0])))
    return np.asarray(room + k * (v - lowpass(v, dt, tau)) + heating, dtype=np.float64)


def temp_compressor_air(t: Array, rng: np.random.Generator) -> Array:
    """Supply air at 21-27 degC warming by 2-6 K (lag 8-20 s) while the compressor runs (20-60
    s on, 30-90 s off; the first switch within 15 s), read through the sensor's 1-3 s lag."""
    dt = float(t[1] - t[0])
    running = np.zeros_like(t)
    on, now = bool(rng.uniform() < 0.5), float(rng.uniform(0.0, 15.0))
    running[t < now] = float(on)
    while now < t[-1]:
        on = not on
        length = float(rng.uniform(20.0, 60.0) if on else rng.uniform(30.0, 90.0))
        running[(t >= now) & (t < now + length)] = float(on)
        now += length
    warm = lowpass(running * float(rng.uniform(2.0, 6.0)), dt, float(rng.uniform(8.0, 20.0)))
    return lowpass(float(rng.uniform(21.0, 27.0)) + warm, dt, float(rng.uniform(1.0, 3.0)))


LOAD_PATTERNS = {"incline_cart": load_incline_cart, "electromagnet_steps": load_electromagnet_steps}
TEMPERATURE_PATTERNS = ("compression_thermocouple", "compressor_air")


def columns(t: Array, v: Array, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record whose muscle pressure is ``v`` [share of
    peak], and their pattern names (independent of the effect)."""
    load_name = tuple(LOAD_PATTERNS)[int(rng.integers(0, len(LOAD_PATTERNS)))]
    temp_name = TEMPERATURE_PATTERNS[int(rng.integers(0, len(TEMPERATURE_PATTERNS)))]
    load = LOAD_PATTERNS[load_name](t, rng)
    if temp_name == "compression_thermocouple":
        temperature = temp_compression_thermocouple(t, rng, v)
    else:
        temperature = temp_compressor_air(t, rng)
    return load, temperature, load_name, temp_name


# ---- effects -------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "bergstrom_boyce_bladder":  # force at unit network strain / top force; tau [s]; power; stretch floor
        return {
            "network_share": rng.uniform(0.5, 2.0),
            "bb_tau_s": rng.uniform(0.1, 0.5),
            "bb_power": rng.uniform(1.3, 2.0),
            "bb_xi": rng.uniform(0.2, 0.5),
        }
    if form == "pressure_stiffened_payload":  # 1 / omega^2 at the top [s^2] (2.5-6 Hz); stiffness floor; damping
        return {
            "mass_s2": (2.0 * math.pi * rng.uniform(2.5, 6.0)) ** -2,
            "stiffness_floor": rng.uniform(0.15, 0.5),
            "payload_zeta": rng.uniform(0.08, 0.25),
        }
    if form == "doi_edwards_reptation":  # effective pressure relaxed [share of a change]; tau_d [s]
        return {"reptation_share": rng.uniform(0.02, 0.06), "reptation_tau_s": rng.uniform(6.0, 25.0)}
    if form == "mittag_leffler_sleeve":  # creep share; tau [s]; fractional order
        return {
            "ml_share": rng.uniform(0.03, 0.1),
            "ml_tau_s": rng.uniform(2.0, 15.0),
            "ml_alpha": rng.uniform(0.3, 0.7),
        }
    if form == "acoustic_line_lag":  # line length [m]; lag per metre [s/m]; lag growth with the volume
        return {
            "line_m": rng.uniform(3.0, 12.0),
            "tau_per_m_s": rng.uniform(0.002, 0.006),
            "volume_growth": rng.uniform(0.5, 1.5),
        }
    if (
        form == "one_euro_filter"
    ):  # time constant when still [s]; speed doubling the cut-off [mm/s]; derivative cut-off [Hz]
        return {"min_tau_s": rng.uniform(0.02, 0.08), "speed_half_mm_s": rng.uniform(5.0, 30.0), "d_cutoff_hz": 1.0}
    if form == "force_length_map":  # the payload's lever (mechanical advantage against the muscle)
        return {"lever_ratio": rng.uniform(2.0, 6.0)}
    if form == "vented_elongation":  # stretch scale [mm]; softening load [kg]; braid engagement [share of peak]
        return {
            "elong_mm": rng.uniform(0.8, 3.0),
            "elong_soft_kg": rng.uniform(0.5, 2.0),
            "engage_share": rng.uniform(0.25, 0.5),
        }
    if form == "bladder_modulus_softening":  # modulus change [1/K]; bladder's lag [s]
        return {"softening_per_k": rng.uniform(0.01, 0.03), "bladder_tau_s": rng.uniform(5.0, 20.0)}
    if form == "thermal_elongation":  # linear expansion [1/K]; lag [s]; share the braid takes up at the peak
        return {
            "expansion_per_k": rng.uniform(3e-4, 9e-4),
            "thermal_tau_s": rng.uniform(10.0, 40.0),
            "braid_share": rng.uniform(0.3, 0.7),
        }
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND9_FORMS}")


def hereditary(dx: Array, kernel: Array) -> Array:
    """``sum_k dx_k kernel(t - t_k)`` (Boltzmann superposition; FFT convolution)."""
    n = 1 << int(math.ceil(math.log2(2 * dx.size)))
    return np.asarray(np.fft.irfft(np.fft.rfft(dx, n) * np.fft.rfft(kernel, n), n)[: dx.size], dtype=np.float64)


def doi_edwards_relaxation(t: Array, tau_s: float) -> Array:
    """The reptation relaxation ``G(t) = sum_(p odd) 8 / (pi^2 p^2) exp(-p^2 t / tau_d)``, scaled to
    ``G(0) = 1`` (:data:`REPTATION_MODES` modes)."""
    p = 2.0 * np.arange(REPTATION_MODES, dtype=np.float64) + 1.0
    weights = 8.0 / (math.pi**2 * p * p)
    g = np.exp(-np.outer(t / tau_s, p * p)) @ weights
    return np.asarray(g / weights.sum(), dtype=np.float64)


def mittag_leffler_decay(s: Array, alpha: float) -> Array:
    """``E_alpha(-s^alpha)`` for ``s >= 0``, ``0 < alpha < 1``, by its spectral integral
    ``int_0^inf exp(-r s) sin(alpha pi) r^(alpha - 1) / (pi (r^(2 alpha) + 2 r^alpha cos(alpha pi) +
    1)) dr`` (on a logarithmic grid of ``r`` and of ``s``, interpolated)."""
    w = np.linspace(-40.0, 40.0, 4001)
    r = np.exp(w)
    spectrum = (
        math.sin(alpha * math.pi)
        * r**alpha
        / (math.pi * (r ** (2 * alpha) + 2 * r**alpha * math.cos(alpha * math.pi) + 1))
    )
    grid = np.logspace(-8.0, 8.0, 321)
    values = np.trapezoid(np.exp(-np.outer(grid, r)) * spectrum, w, axis=1)
    out = np.interp(np.log(np.clip(s, 1e-8, 1e8)), np.log(grid), values)
    return np.asarray(np.where(s <= 0.0, 1.0, out), dtype=np.float64)


def bergstrom_boyce_force(e: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The viscous network's strain ``phi`` (its force is ``network_share x phi`` of the top
    force) for the bladder's strain ``e`` [share of the stroke]: ``phi`` follows every change of
    ``e`` and flows away as ``dphi/dt = -(1 + xi) / (tau (|e_v| + xi)) |phi|^m sign(phi)`` (exact
    over a sample), ``e_v = e - phi`` the flowed strain; from rest."""
    tau, m, xi = q["bb_tau_s"], q["bb_power"], q["bb_xi"]
    out = np.empty(e.size)
    phi, prev = 0.0, float(e[0])
    for i, ei in enumerate(e.tolist()):
        phi += ei - prev
        if phi != 0.0:
            rate = (1.0 + xi) / (tau * (abs(ei - phi) + xi))
            mag = (abs(phi) ** (1.0 - m) + (m - 1.0) * rate * dt_s) ** (1.0 / (1.0 - m))
            phi = math.copysign(mag, phi)
        out[i] = phi
        prev = ei
    return out


def stiffened_payload(x: Array, v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The payload's stroke [mm] following ``x`` on a stiffness ``(s0 + v) / (s0 + 1)`` of its
    value at the top (``y'' = w(v)^2 (x - y) - 2 zeta w(v) y'``, ``w`` at the top ``1 / sqrt(mass_s2)``;
    semi-implicit Euler sub-stepped so that ``w dt <= 0.2``, ``x`` joined linearly), from rest on
    ``x[0]``."""
    w_top, s0, zeta = 1.0 / math.sqrt(q["mass_s2"]), q["stiffness_floor"], q["payload_zeta"]
    subs = max(1, int(math.ceil(w_top * math.sqrt((s0 + 1.2) / (s0 + 1.0)) * dt_s / 0.2)))
    h = dt_s / subs
    out = np.empty(x.size)
    y, speed, prev = float(x[0]), 0.0, float(x[0])
    for i, (xi, vi) in enumerate(zip(x.tolist(), v.tolist())):
        w = w_top * math.sqrt((s0 + max(vi, 0.0)) / (s0 + 1.0))
        for k in range(1, subs + 1):
            target = prev + (xi - prev) * k / subs
            speed += h * (w * w * (target - y) - 2.0 * zeta * w * speed)
            y += h * speed
        out[i] = y
        prev = xi
    return out


def line_pressure(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The muscle's pressure [share of peak] at the end of the line from the manifold's ``v``: the
    acoustic dead time ``line_m / c`` then a lag ``line_m tau_per_m (1 + growth v)`` (exact for a
    value held over each sample)."""
    delayed = variable_delay(v, np.full_like(v, q["line_m"] / SOUND_M_S / dt_s))
    base_tau, growth = q["line_m"] * q["tau_per_m_s"], q["volume_growth"]
    out = np.empty(v.size)
    y = float(delayed[0])
    for i, vi in enumerate(delayed.tolist()):
        y += (vi - y) * (1.0 - math.exp(-dt_s / (base_tau * (1.0 + growth * max(y, 0.0)))))
        out[i] = y
    return out


def one_euro(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The One-Euro filter of ``x`` [mm]: an exponential smoother whose cut-off ``(1 + |x'| /
    speed_half) / (2 pi min_tau)`` rises with the speed ``x'`` (the raw samples' difference, smoothed at
    ``d_cutoff_hz``); from rest on ``x[0]``."""
    tau_min, v_half = q["min_tau_s"], q["speed_half_mm_s"]
    a_d = 1.0 / (1.0 + 1.0 / (2.0 * math.pi * q["d_cutoff_hz"] * dt_s))
    out = np.empty(x.size)
    y, speed, prev = float(x[0]), 0.0, float(x[0])
    for i, xi in enumerate(x.tolist()):
        speed += a_d * ((xi - prev) / dt_s - speed)
        prev = xi
        tau = tau_min / (1.0 + abs(speed) / v_half)
        y += (xi - y) / (1.0 + tau / dt_s)
        out[i] = y
    return out


def elongation_mm(load: Array, q: dict[str, float]) -> Array:
    """The vented muscle's stretch [mm] under ``load`` [kg]: ``elong_mm log(1 + load / soft)``."""
    return np.asarray(q["elong_mm"] * np.log1p(np.clip(load, 0.0, None) / q["elong_soft_kg"]), dtype=np.float64)


def braid_gate(v: Array, q: dict[str, float]) -> Array:
    """The share of the payload the bladder carries: ``(1 - v / engage)^2``, 0 once the braid engages."""
    return np.asarray(np.clip(1.0 - v / q["engage_share"], 0.0, 1.0) ** 2, dtype=np.float64)


def render(
    plant: str,
    params: dict[str, float],
    u: Array,
    dt_s: float,
    form: str,
    q: dict[str, float],
    load: Array,
    temperature: Array,
    base: Array,
) -> Array:
    """Noise-free stroke reading [mm] of ``plant`` (its contraction ``base`` for the set pressure
    ``u`` [bar]) with the effect ``form`` (``"none"``: switched off), through the rig
    (:func:`~bench.plants.blind9_rig.stroke_reading`).

    The load and temperature forms act through their column's change since the record's start
    (the plant as identified then): with the columns held at their first value they are the
    effect-free plant."""
    x = base
    if form in INSIDE_FORMS:
        drive = BLIND9_DRIVES[plant]
        v = normalised_pressure(u, dt_s, params)
        if form == "bergstrom_boyce_bladder":
            phi = bergstrom_boyce_force(base / params["stroke_mm"], dt_s, q)
            x = drive(v, dt_s, params, {"f_ext": q["network_share"] * params["top_force_n"] * phi})
        elif form == "doi_edwards_reptation":
            t = np.arange(v.size, dtype=np.float64) * dt_s
            creep = hereditary(np.diff(v, prepend=v[0]), 1.0 - doi_edwards_relaxation(t, q["reptation_tau_s"]))
            x = drive(v, dt_s, params, {"dv": q["reptation_share"] * creep})
        elif form == "acoustic_line_lag":
            x = drive(line_pressure(v, dt_s, q), dt_s, params, {})
        elif form == "force_length_map":
            x = drive(v, dt_s, params, {"f_ext": q["lever_ratio"] * G_MS2 * (load - load[0])})
        else:  # bladder_modulus_softening
            warm = lowpass(temperature, dt_s, q["bladder_tau_s"])
            soft = np.clip(1.0 - q["softening_per_k"] * (warm - warm[0]), 0.2, None)
            x = drive(v, dt_s, params, {"rubber": soft})
    elif form == "pressure_stiffened_payload":
        x = stiffened_payload(x, normalised_pressure(u, dt_s, params), dt_s, q)
    elif form == "mittag_leffler_sleeve":
        t = np.arange(x.size, dtype=np.float64) * dt_s
        kernel = 1.0 - mittag_leffler_decay(t / q["ml_tau_s"], q["ml_alpha"])
        x = x + q["ml_share"] * hereditary(np.diff(x, prepend=x[0]), kernel)
    elif form == "vented_elongation":
        gate = braid_gate(normalised_pressure(u, dt_s, params), q)
        x = x - (elongation_mm(load, q) - elongation_mm(np.full_like(load, load[0]), q)) * gate
    elif form == "thermal_elongation":
        warm = lowpass(temperature, dt_s, q["thermal_tau_s"])
        taken = 1.0 - q["braid_share"] * np.clip(normalised_pressure(u, dt_s, params), 0.0, 1.2)
        x = x - q["expansion_per_k"] * params["length_mm"] * (warm - warm[0]) * taken
    reading = stroke_reading(x, u, dt_s, params)
    if form == "one_euro_filter":
        reading = one_euro(reading, dt_s, q)
    return reading
