"""Online adaptation of the model's output map, by recursive least squares with forgetting.

The muscle drifts between sessions (the real 18-03 and 31-03 campaigns of one muscle differ by
a shift of the pressure-contraction map) and a model identified on one run is off by an offset
and a gain on the next (the piezo validation runs). Each tick :class:`OutputMapEstimator`
updates ``a`` (offset, output units) and ``b`` (gain) of::

    y_plant ~ a + b * y_model

from the twin's prediction ``y_model`` and the measured output, with exponential forgetting
(memory ``memory_s``). The feedforward then asks the inverse for ``(r - a) / b`` instead of
``r``, so the model and the map together deliver ``r``.

Safeguards (all in :class:`AdaptSettings`, one place):

* **bounded**: ``|a| <= offset_max_share * span`` and ``gain_min <= b <= gain_max``, where
  ``span`` is the model's output span (the bundle's reach), so one setting serves any unit;
* **frozen without excitation**: the estimate (and its covariance, so it cannot wind up) is
  updated only while the standard deviation of ``y_model`` over the last
  ``excitation_window_s`` (exponentially weighted) is at least ``excitation_share * span``:
  with a resting input the offset and the gain cannot be told apart;
* **reset on arming** to ``a = 0, b = 1``; the covariance never grows past its initial value.

Plain Python floats, no numpy: the edge runs it per tick, and ``pmactl fit --adapt`` replays
this same code over recordings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class AdaptSettings:
    """The ``[adapt]`` section of the rig config (shares are of the model's output span)."""

    enabled: bool = False
    memory_s: float = 5.0  # forgetting time constant: lambda = exp(-dt / memory_s)
    offset_max_share: float = 0.25  # |a| bound, share of the output span
    gain_min: float = 0.6
    gain_max: float = 1.6
    excitation_share: float = 0.05  # freeze while std(y_model) over the window is below this share of the span
    excitation_window_s: float = 1.0


class OutputMapEstimator:
    """RLS estimate of ``a`` and ``b`` in ``y ~ a + b * y_model`` (see the module docstring).

    Args:
        settings: the ``[adapt]`` settings.
        dt_s: the time between updates [s] (the tick period, or a recording's sample time).
        span: the model's output span (output units) the shares refer to; must be > 0.
    """

    def __init__(self, settings: AdaptSettings, dt_s: float, span: float) -> None:
        if not (span > 0.0 and math.isfinite(span)):
            raise ValueError(f"output span {span!r} must be a finite number > 0")
        self.settings = settings
        self.forgetting = math.exp(-dt_s / settings.memory_s)
        self.excitation_alpha = 1.0 - math.exp(-dt_s / settings.excitation_window_s)
        self.offset_max = settings.offset_max_share * span
        self.min_variance = (settings.excitation_share * span) ** 2
        # initial covariance: a few samples move the estimate across its whole bound
        self._p0 = (self.offset_max**2, (settings.gain_max - settings.gain_min) ** 2)
        self.reset()

    def reset(self) -> None:
        """Back to the identity map (a = 0, b = 1), frozen until the input excites it."""
        self.offset_, self.gain_ = 0.0, 1.0
        self.excited_ = False
        self.updates_ = 0
        self._p00, self._p01, self._p11 = self._p0[0], 0.0, self._p0[1]
        self._mean = math.nan
        self._var = self._weight = 0.0

    def predict(self, y_model: float) -> float:
        """The mapped model output ``a + b * y_model``."""
        return self.offset_ + self.gain_ * y_model

    def target(self, wanted: float) -> float:
        """What to ask the inverse for so that the mapped output is ``wanted``: ``(wanted - a) / b``."""
        return (wanted - self.offset_) / self.gain_

    def update(self, y_model: float, y_measured: float) -> None:
        """One sample: the model's output and the measured output (NaN skips the sample)."""
        if y_model != y_model or y_measured != y_measured:
            return
        alpha = self.excitation_alpha
        if self._mean != self._mean:
            self._mean = y_model
        else:
            delta = y_model - self._mean
            self._mean += alpha * delta
            self._var = (1.0 - alpha) * (self._var + alpha * delta * delta)
            self._weight += alpha * (1.0 - self._weight)
        # divided by the weight collected so far: right from the first samples, not after a window
        self.excited_ = self._weight > 0.0 and self._var >= self.min_variance * self._weight
        if not self.excited_:
            return
        lam = self.forgetting
        p00, p01, p11 = self._p00, self._p01, self._p11
        g0 = p00 + p01 * y_model  # P phi, phi = (1, y_model)
        g1 = p01 + p11 * y_model
        denominator = lam + g0 + g1 * y_model
        k0, k1 = g0 / denominator, g1 / denominator
        error = y_measured - (self.offset_ + self.gain_ * y_model)
        a = self.offset_ + k0 * error
        b = self.gain_ + k1 * error
        p00, p01, p11 = (p00 - k0 * g0) / lam, (p01 - k0 * g1) / lam, (p11 - k1 * g1) / lam
        # never more uncertain than at the start (forgetting on a weakly exciting input winds P up)
        scale = min(1.0, self._p0[0] / p00 if p00 > 0.0 else 1.0, self._p0[1] / p11 if p11 > 0.0 else 1.0)
        self._p00, self._p01, self._p11 = p00 * scale, p01 * scale, p11 * scale
        s = self.settings
        self.offset_ = min(max(a, -self.offset_max), self.offset_max)
        self.gain_ = min(max(b, s.gain_min), s.gain_max)
        self.updates_ += 1


def replay(
    settings: AdaptSettings, dt_s: float, span: float, y_model: list[float], y_measured: list[float], start: int = 0
) -> list[float]:
    """Run the estimator over a recording as the edge runs it per tick: from sample ``start``,
    the prediction for sample k is ``a + b * y_model[k]`` with the map learned from the samples
    before k (one step ahead; nothing of sample k is in it). NaN before ``start``."""
    estimator = OutputMapEstimator(settings, dt_s, span)
    predicted = [math.nan] * len(y_model)
    for k in range(start, len(y_model)):
        model = y_model[k]
        predicted[k] = estimator.offset_ + estimator.gain_ * model
        estimator.update(model, y_measured[k])
    return predicted
