"""Five excitation protocols [bar, 0..peak] unlike the other families', each after a choked sweep.

What a lab building assistive gloves, cardiac and teleoperated soft devices would run: an
*EMG-proportional* assist (the rectified, smoothed envelope of a surface EMG: bursts of muscle
activity of random strength and length with rests, each burst a band-limited noise through a
linear envelope detector); a *cardiac-assist* pulse train (a systolic push of a raised-cosine
shape each beat, heart rate 60-100 bpm with respiratory sinus arrhythmia, an ectopic early beat
now and then); a *teleoperated* joystick (the operator's moves to set points with a bell-shaped
speed profile, a physiological tremor of 8-12 Hz on top while holding, and pauses with the stick
released to its spring centre); *creep-recovery blocks* (a load ramp of 0.3-1 s to a level, held
6-18 s, a ramp down to a low level, held 6-18 s, the levels redrawn per block); and a *rate
decade*: triangles between two levels whose period falls geometrically by a decade (from
12-20 s to 1.2-2 s) and climbs back.

Every record starts vented (0.3-0.6 s) and does a *choked sweep* in its first ~5 s
(:func:`with_choked_sweep`): the valve opens fully and the muscle fills as under choked flow
(the pressure rising at a falling rate, ``1 - (1 - s)^2``) to 0.98-1 ``peak`` in 1.2-2 s, holds
0.3-1 s, vents linearly to 0 in 1.2-2 s, stays vented 0.4 s and blends in 0.5 s (a raised
cosine) into the protocol's first value.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass
from bench.plants.grids import knotted, time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]


def emg_envelope(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Bursts of 1-4 s (rests 0.5-3 s) of white noise of a strength 0.4-1 per burst, rectified
    and smoothed by a 0.15-0.3 s envelope detector, scaled so that the strongest burst reaches
    ``peak``; a 1-3 % tonic activity stays between the bursts."""
    t = time_grid(duration_s, dt_s)
    strength = np.zeros_like(t)
    now = float(rng.uniform(0.2, 1.0))
    while now < duration_s:
        length = float(rng.uniform(1.0, 4.0))
        strength[(t >= now) & (t < now + length)] = float(rng.uniform(0.4, 1.0))
        now += length + float(rng.uniform(0.5, 3.0))
    tonic = float(rng.uniform(0.01, 0.03))
    raw = np.abs(rng.normal(0.0, 1.0, t.size)) * (strength + tonic)
    env = lowpass(lowpass(raw, dt_s, float(rng.uniform(0.15, 0.3))), dt_s, 0.05)
    top = float(np.max(env)) if env.size else 1.0
    return np.asarray(peak * np.clip(env / max(top, 1e-9), 0.0, 1.0), dtype=np.float64)


def cardiac_assist(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """One systolic push per beat: a raised cosine of 30-40 % of the beat to 0.5-0.95 ``peak``
    (redrawn per beat, +-5 %), vented in diastole; the heart rate 60-100 bpm is modulated by
    breathing (+-3-8 bpm at 0.2-0.3 Hz); 3 % of the beats come 30 % early (ectopic)."""
    t = time_grid(duration_s, dt_s)
    out = np.zeros_like(t)
    hr, swing, breath = float(rng.uniform(60.0, 100.0)), float(rng.uniform(3.0, 8.0)), float(rng.uniform(0.2, 0.3))
    level, share = float(rng.uniform(0.5, 0.95)), float(rng.uniform(0.3, 0.4))
    now = 0.0
    while now < duration_s:
        beat = 60.0 / (hr + swing * np.sin(2 * np.pi * breath * now))
        if rng.random() < 0.03:
            beat *= 0.7
        push = share * beat
        s = (t - now) / push
        inside = (s >= 0.0) & (s < 1.0)
        amp = peak * min(level * float(rng.uniform(0.95, 1.05)), 1.0)
        out[inside] = amp * 0.5 * (1.0 - np.cos(2.0 * np.pi * s[inside]))
        now += beat
    return out


def joystick_teleop(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Moves between set points (0-1 ``peak``, uniform) lasting 0.3-1.5 s with a minimum-jerk-
    like bell speed profile (a smoothstep of order 5), holds of 0.5-4 s with a physiological
    tremor (8-12 Hz, 0.3-1 % of ``peak``), and every 10-25 s the stick released to its spring
    centre (vented) for 1-3 s."""
    t = time_grid(duration_s, dt_s)
    knots_t, knots_u = [0.0], [0.0]
    release = float(rng.uniform(10.0, 25.0))
    while knots_t[-1] < duration_s:
        if knots_t[-1] >= release:
            target, release = 0.0, knots_t[-1] + float(rng.uniform(10.0, 25.0))
            hold = float(rng.uniform(1.0, 3.0))
        else:
            target, hold = float(rng.uniform(0.0, 1.0)), float(rng.uniform(0.5, 4.0))
        knots_t += [knots_t[-1] + float(rng.uniform(0.3, 1.5)), 0.0]
        knots_t[-1] = knots_t[-2] + hold
        knots_u += [target, target]
    kt, ku = np.asarray(knots_t), np.asarray(knots_u)
    idx = np.clip(np.searchsorted(kt, t, side="right") - 1, 0, kt.size - 2)
    s = np.clip((t - kt[idx]) / np.maximum(kt[idx + 1] - kt[idx], 1e-9), 0.0, 1.0)
    smooth = s**3 * (10.0 - 15.0 * s + 6.0 * s * s)
    level = ku[idx] + (ku[idx + 1] - ku[idx]) * smooth
    tremor = float(rng.uniform(0.003, 0.01)) * np.sin(2 * np.pi * float(rng.uniform(8.0, 12.0)) * t) * (level > 0.02)
    return np.asarray(peak * np.clip(level + tremor, 0.0, 1.0), dtype=np.float64)


def creep_recovery_blocks(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Blocks: a ramp of 0.3-1 s to 0.55-1 ``peak``, held 6-18 s, a ramp of 0.3-1 s down to
    0-0.3 ``peak``, held 6-18 s (the levels redrawn per block)."""
    knots_t, knots_u = [0.0], [0.0]
    while knots_t[-1] < duration_s:
        for level in (float(rng.uniform(0.55, 1.0)), float(rng.uniform(0.0, 0.3))):
            ramp, hold = float(rng.uniform(0.3, 1.0)), float(rng.uniform(6.0, 18.0))
            knots_t += [knots_t[-1] + ramp, knots_t[-1] + ramp + hold]
            knots_u += [peak * level, peak * level]
    return knotted(duration_s, dt_s, knots_t, knots_u)


def rate_decade(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Triangles between 0.02-0.15 and 0.8-1 ``peak`` whose period falls geometrically from
    12-20 s to a tenth of it over 8-12 cycles and climbs back, repeated."""
    lo, hi = float(rng.uniform(0.02, 0.15)), float(rng.uniform(0.8, 1.0))
    slow, cycles = float(rng.uniform(12.0, 20.0)), int(rng.integers(8, 13))
    periods = np.geomspace(slow, slow / 10.0, cycles)
    sweep = np.concatenate([periods, periods[::-1]])
    knots_t, knots_u = [0.0], [lo]
    while knots_t[-1] < duration_s:
        for period in sweep.tolist():
            knots_t += [knots_t[-1] + 0.5 * period, knots_t[-1] + period]
            knots_u += [hi, lo]
    return peak * knotted(duration_s, dt_s, knots_t, knots_u)


BLIND6_PROTOCOLS: dict[str, Protocol] = {
    "emg_envelope": emg_envelope,
    "cardiac_assist": cardiac_assist,
    "joystick_teleop": joystick_teleop,
    "creep_recovery_blocks": creep_recovery_blocks,
    "rate_decade": rate_decade,
}


def with_choked_sweep(protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """0.3-0.6 s vented, a choked fill ``1 - (1 - s)^2`` to 0.98-1 ``peak`` in 1.2-2 s, a 0.3-1 s
    hold, a linear vent to 0 in 1.2-2 s, 0.4 s vented, a 0.5 s raised-cosine blend to the
    protocol's first value, then ``protocol`` [0..peak] to ``duration_s``."""
    vented, fill, hold, vent = (float(rng.uniform(a, b)) for a, b in ((0.3, 0.6), (1.2, 2.0), (0.3, 1.0), (1.2, 2.0)))
    top = float(rng.uniform(0.98, 1.0)) * peak
    vent_at = vented + fill + hold
    lead_s = vent_at + vent + 0.9
    body = np.clip(BLIND6_PROTOCOLS[protocol](max(duration_s - lead_s, 0.0) + 1.0, dt_s, peak, rng), 0.0, peak)
    t = time_grid(lead_s, dt_s)
    s_fill = np.clip((t - vented) / fill, 0.0, 1.0)
    filled = top * (1.0 - (1.0 - s_fill) ** 2)
    emptied = top * np.clip(1.0 - (t - vent_at) / vent, 0.0, 1.0)
    lead = np.where(t < vent_at, filled, emptied)
    blend = 0.5 * (1.0 - np.cos(np.pi * np.clip((t - (lead_s - 0.5)) / 0.5, 0.0, 1.0)))
    lead = lead + blend * float(body[0])
    return np.asarray(np.concatenate([lead, body])[: int(round(duration_s / dt_s))], dtype=np.float64)
