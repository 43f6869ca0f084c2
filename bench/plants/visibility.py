"""The visibility rule the held-out plant families share: an effect's size (RMS [mm] of the
noise-free output with the effect minus the same record with it off) lies in
``[EFFECT_MIN_OVER_NOISE * noise, EFFECT_MAX_OVER_SPAN * span]``; a drawn intensity outside it
is scaled, at most :data:`MAX_RESCALE` x either way, until it lands there."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
EFFECT_MIN_OVER_NOISE = 5.0  # the brief asks >= 4x; 5x leaves room for the noise of the estimate
EFFECT_MAX_OVER_SPAN = 0.12  # the brief asks <= ~15 %
MAX_RESCALE = 4.0
RESCALE_PASSES = 8
MAX_CALIBRATION = 3.0  # a calibrated family moves its drawn intensity at most 3 x either way, to stay plausible


def rms(x: Array) -> float:
    return float(np.sqrt(np.mean(x * x)))


def scale_into_band(
    render_on: Callable[[], Array],
    off: Array,
    noise: float,
    span: float,
    q: dict[str, float],
    key: str,
    grow: float,
) -> tuple[Array, float, float]:
    """Render the effect (``render_on`` reads ``q``), scaling ``q[key]`` until its size lies in
    the band: by ``grow`` x the missing share when too small, to 85 % of the top when too large.
    Returns the output with the effect, its size [mm] and the total rescale (``q`` is updated).
    At the rescale limit the record is kept as it is (the families' tests catch it)."""
    lo, hi = EFFECT_MIN_OVER_NOISE * noise, EFFECT_MAX_OVER_SPAN * span
    on, size, rescale = off, 0.0, 1.0
    for _ in range(RESCALE_PASSES):
        on = render_on()
        size = rms(on - off)
        if lo <= size <= hi:
            break
        step = grow * lo / max(size, 1e-12) if size < lo else 0.85 * hi / size
        step = float(np.clip(step, 1.0 / MAX_RESCALE / rescale, MAX_RESCALE / rescale))
        if abs(step - 1.0) < 1e-9:
            break
        q[key] *= step
        rescale *= step
    return on, size, rescale


def visible_effect(
    effect: str,
    form: str,
    render_on: Callable[[], Array],
    off: Array,
    noise: float,
    q: dict[str, float],
    key: str,
    grow: float,
    plant_parameters: dict[str, float],
    patterns: tuple[str, str],
) -> tuple[Array, dict[str, Any]]:
    """The output with ``effect`` scaled into the band (``off`` itself for ``"none"``) and the
    truth record every held-out family keeps: effect, form, parameters, size [mm] and its ratio
    to the noise and the span, the rescale, and the load and temperature patterns."""
    span = float(np.ptp(off))
    on, size, rescale = off, 0.0, 1.0
    if effect != "none":
        on, size, rescale = scale_into_band(render_on, off, noise, span, q, key, grow=grow)
    truth: dict[str, Any] = {
        "effect": effect,
        "form": form,
        "parameters": dict(q),
        "plant_parameters": dict(plant_parameters),
        "effect_size": size,
        "effect_size_over_noise": size / noise,
        "effect_size_over_span": size / span,
        "intensity_rescale": rescale,
        "noise": noise,
        "span": span,
        "load_pattern": patterns[0],
        "temperature_pattern": patterns[1],
    }
    return on, truth


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
