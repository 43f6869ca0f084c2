"""``pmactl fit --test ... --adapt``: the held-out error with the edge's online adaptation.

The edge's own estimator (:func:`edge.control.adapt.replay`, the code the rig runs each tick)
is replayed over each held-out recording: the model is simulated from the start state chosen
on the calibration window (as the plain score does, :mod:`host.evaluate`), the estimator starts
at the identity map where the input starts moving and predicts every sample from the samples
before it. The calibration offset is not used; the score is taken on the same samples as the
plain score (after the calibration window), so the two columns compare like for like.
"""

from __future__ import annotations

import numpy as np

from edge.control.adapt import AdaptSettings, replay
from host.data import Measurement
from host.evaluate import Score, score
from host.workflow import TestResult


def adapted_score(result: TestResult, test: Measurement, span: float, settings: AdaptSettings) -> Score:
    """The score of ``result``'s recording ``test`` with the output map adapted online.

    ``span`` is the model's output span (the training output's peak-to-peak), which the
    adaptation's bounds and excitation threshold are shares of."""
    prediction = result.prediction
    shape = prediction.y - prediction.offset  # the model's own output, no calibrated offset
    adapted = np.array(replay(settings, float(test.dt), span, shape.tolist(), test.y.tolist(), prediction.window_start))
    end = prediction.window_end
    return score(test.y[end:], adapted[end:])
