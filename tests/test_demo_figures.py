"""The closed-loop figure: every controller on one reference, the error axis fitted to the scored part."""

from __future__ import annotations

import numpy as np

from host.demo_figures import _scored_limits, plot_tracking


def run(seed: int) -> dict[str, np.ndarray]:
    t = np.arange(0, 10, 0.01)
    reference = 40 + 30 * np.sin(2 * np.pi * 0.2 * t)
    output = reference + np.random.default_rng(seed).normal(0, 0.5, t.size)
    output[:20] = 0.0  # the loop starts from rest: a 40 mm error before it is scored
    return {
        "t": t,
        "reference": reference,
        "output": output,
        "command_bar": reference / 12,
        "pressure_bar": reference / 12,
    }


def test_the_error_axis_fits_the_scored_part_not_the_start():
    t = np.arange(0, 10, 0.01)
    error = run(0)["output"] - run(0)["reference"]
    low, high = _scored_limits([error[t >= 2.0]])
    assert -5 < low < 0 < high < 5 and error.min() < -30


def test_the_tracking_figure_is_written(tmp_path):
    path = plot_tracking(
        tmp_path / "t.png", {"PID": run(1), "PID + ff": run(2)}, 2.0, (0.0, 60.0), {"PID": 1.0, "PID + ff": 0.5}
    )
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 20_000
