"""Maxwell-slip friction: recovery on synthetic elements, element choice, the real cylinder loops."""

from __future__ import annotations

import json

import numpy as np
import pytest

from host.cli import main
from host.identify.maxwell_slip import MaxwellSlip, select_and_fit, slip_stretches


def synthetic(seed: int):
    """Known elements (slip 0.2, 1, 4 mm) driven by a random walk of decaying sweeps, plus 0.1 N noise."""
    rng = np.random.default_rng(seed)
    turns = 20.0 * rng.uniform(0.2, 1.0, 40) * np.where(np.arange(40) % 2 == 0, 1, -1)
    x = np.concatenate([np.linspace(a, b, 150) for a, b in zip(np.r_[0.0, turns[:-1]], turns)])
    slip = np.array([0.2, 1.0, 4.0])
    stiffness = np.array([20.0, 5.0, 1.5])
    force = 100.0 + 0.3 * x + slip_stretches(x, slip) @ stiffness
    return x, force + rng.normal(0, 0.1, x.size), slip * stiffness


def test_element_law_is_elastoplastic():
    s = slip_stretches(np.array([0.0, 0.5, 3.0, 2.0]), np.array([1.0]))[:, 0]
    np.testing.assert_allclose(s, [0.0, 0.5, 1.0, 0.0])


def test_despike_removes_single_sample_glitches_and_keeps_ramps():
    from host.identify.maxwell_slip import despike

    ramp = np.linspace(0, 5, 11)
    np.testing.assert_allclose(despike(ramp), ramp)
    glitch = ramp.copy()
    glitch[4] += 3.0
    # the glitch is gone; no sample moves by more than one step of the ramp
    assert np.max(np.abs(despike(glitch) - ramp)) <= 0.5 + 1e-12


def test_recovers_known_break_forces():
    x, force, breaks = synthetic(0)
    model = MaxwellSlip(3).fit(x, force)
    residual = model.predict(x) - force
    # the slip displacements come from a grid, not the truth: a few % of the range, not the noise
    assert np.sqrt(np.mean(residual[100:] ** 2)) < 0.05 * np.ptp(force)
    assert model.break_force_.sum() == pytest.approx(breaks.sum(), rel=0.15)
    assert model.linear_stiffness_ == pytest.approx(0.3, rel=0.2)


def test_held_out_choice_prefers_enough_elements():
    x, force, _ = synthetic(1)
    result = select_and_fit(x, force, max_elements=5)
    assert result.model.elements >= 2
    one = next(row for row in result.scan if row["elements"] == 1)
    assert result.test_rmse < one["test_rmse"]


@pytest.mark.parametrize("name", ["Kidney_lc_3bar.csv", "O-ring_5bar.csv"])
def test_real_cylinder_loops(shared_data, name, capsys):
    path = shared_data / "pneumatic_cylinder_friction" / name
    if not path.exists():
        pytest.skip(f"{path} absent")
    assert main(["identify", "maxwell-slip", str(path), "--elements", "3", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["heldout_rmse_pct_range"] < 10.0
    # friction loops: the elements carry a real break force
    assert sum(out["break_force_n"]) > 1.0


def test_more_elements_than_the_data_can_identify_are_refused_with_the_limit(tmp_path, capsys):
    x, force, _ = synthetic(4)
    path = tmp_path / "short.csv"
    path.write_text("x,force\n" + "".join(f"{a},{b}\n" for a, b in zip(x[:50], force[:50])))
    assert main(["identify", "maxwell-slip", str(path), "--elements", "1000"]) == 2
    err = capsys.readouterr().err
    # 50 samples: 35 in the fit window, 2 of them warm-up, 33 for 2 + 2 N parameters -> N <= 15
    assert "--elements 1000" in err and "at most 15 element(s)" in err and "--elements 15 or fewer" in err
    assert main(["identify", "maxwell-slip", str(path), "--elements", "15", "--json"]) == 0
