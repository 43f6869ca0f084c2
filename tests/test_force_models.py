"""Static force laws: recovery, fits across laws (not circular), inverses, the HIL's force protocols, CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hil.plant import PlantParams
from hil.record import record, write_recording
from host.cli import main
from host.identify.force import SarosiForce, TonduLopezForce

SAROSI_TRUE = {"a": 150.0, "b": -0.08, "c": -0.05, "d": 2.0, "e": -150.0}


def sarosi_data(seed: int, noise_n: float = 2.0):
    """Force from Sarosi's law (Ai2019 eq 15), a second law the HIL does not use."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(0.5, 6.0, 500)
    eps = rng.uniform(0.0, 0.2, 500)
    pk, kappa = p * 100, eps * 100
    s = SAROSI_TRUE
    force = (pk + s["a"]) * np.exp(s["b"] * kappa) + s["c"] * pk * kappa + s["d"] * pk + s["e"]
    return p, eps, force + rng.normal(0, noise_n, p.size)


def chou_hannaford_data(seed: int):
    """Chou-Hannaford virtual work with wall thickness (their eq with t_k): another foreign law."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(0.5, 6.0, 500)
    eps = rng.uniform(0.0, 0.2, 500)
    d0, theta0, wall = 0.02, np.radians(25.0), 0.0015
    cos_t = np.cos(theta0) * (1 - eps)
    sin_t = np.sqrt(1 - cos_t**2)
    pa = p * 1e5
    force = (np.pi * d0**2 * pa / 4) * (3 * cos_t**2 - 1) / np.sin(theta0) ** 2
    force += np.pi * pa * (d0 * wall * (2 * np.sin(theta0) - 1 / np.sin(theta0)) - wall**2) * sin_t / np.sin(theta0)
    return p, eps, force + rng.normal(0, 2.0, p.size)


def test_sarosi_recovers_its_parameters():
    model = SarosiForce().fit(*sarosi_data(0))
    for name, value in SAROSI_TRUE.items():
        fitted, se = getattr(model, f"{name}_"), model.se_["abcde".index(name)]
        assert abs(fitted - value) < 4 * se + 1e-6 * abs(value), name
    assert model.rmse_n_ == pytest.approx(2.0, rel=0.15)


@pytest.mark.parametrize("law", [sarosi_data, chou_hannaford_data])
def test_tondu_lopez_fits_a_foreign_law(law):
    """Tondu-Lopez explains another law to a few % of the force range: the fit is not tied to our emulator."""
    p, eps, force = law(1)
    model = TonduLopezForce(radius_m=0.01).fit(p, eps, force)
    assert model.rmse_n_ < 0.03 * np.ptp(force)
    assert np.all(np.isfinite(model.se_))


def test_sarosi_fits_chou_hannaford():
    p, eps, force = chou_hannaford_data(2)
    assert SarosiForce().fit(p, eps, force).rmse_n_ < 0.02 * np.ptp(force)


@pytest.mark.parametrize("cls", [TonduLopezForce, SarosiForce])
def test_pressure_inverts_predict(cls):
    p, eps, force = sarosi_data(3, noise_n=0.0)
    model = cls().fit(p, eps, force)
    predicted = model.predict(p, eps)
    back = model.pressure(predicted, eps)
    ok = np.isfinite(back)
    assert ok.mean() > 0.9
    np.testing.assert_allclose(back[ok], p[ok], rtol=1e-9, atol=1e-9)


def test_force_fit_refuses_data_without_variation():
    with pytest.raises(ValueError, match="does not vary"):
        TonduLopezForce().fit(np.full(20, 3.0), np.linspace(0, 0.1, 20), np.linspace(100, 50, 20))


def test_hil_isometric_recovers_the_rig_tondu_lopez():
    """Circular by construction (the HIL's muscle is Tondu-Lopez): a check of the protocol and units."""
    rec = record("isometric", 1, 60.0, rate_hz=50.0)
    params = PlantParams()
    assert rec.force is not None
    model = TonduLopezForce(params.radius_m).fit(rec.p, rec.y / 1e3 / params.rest_length_m, rec.force)
    assert model.a_ == pytest.approx(params.tondu_a, rel=0.02)
    assert model.b_ == pytest.approx(params.tondu_b, rel=0.03)
    assert model.k_ == pytest.approx(params.tondu_k, rel=0.02)


def test_cli_force_on_an_isotonic_hil_recording(tmp_path, capsys):
    rec = record("isotonic", 2, 80.0, effect="load_dependence", rate_hz=20.0)
    path = write_recording(rec, tmp_path / "iso.csv")
    assert path.read_text().splitlines()[0] == "t,u,y,p,load,temperature,force"
    assert main(["identify", "force", str(path), "--model", "sarosi", "--rest-length-mm", "400", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    # the braid friction (+-30 N) is what a static law cannot explain on isotonic loops
    assert out["rmse_n"] < 40.0 and out["force_column"] == "force"
    assert main(["identify", "force", str(path), "--model", "tondu-lopez"]) == 2
    assert "--rest-length-mm" in capsys.readouterr().err


def _small_force_csv(path):  # noqa: ANN001, ANN202
    p, eps, force = sarosi_data(3)
    rows = "".join(f"{a},{400 * b},{c}\n" for a, b, c in zip(p, eps, force))
    path.write_text("p,y,force\n" + rows)
    return path


@pytest.mark.parametrize("value", ["nan", "inf", "0", "-400"])
def test_a_rest_length_that_is_not_a_finite_positive_number_is_named(tmp_path, capsys, value):
    path = _small_force_csv(tmp_path / "f.csv")
    assert main(["identify", "force", str(path), "--model", "sarosi", f"--rest-length-mm={value}"]) == 2
    err = capsys.readouterr().err
    assert "--rest-length-mm" in err and "must be a finite positive number" in err and "pass --rest" not in err


@pytest.mark.parametrize("value", ["-3", "0", "nan"])
def test_a_radius_that_is_not_a_finite_positive_number_is_refused(tmp_path, capsys, value):
    path = _small_force_csv(tmp_path / "f.csv")
    argv = ["identify", "force", str(path), "--model", "tondu-lopez", "--rest-length-mm", "400"]
    assert main([*argv, f"--radius-mm={value}"]) == 2
    err = capsys.readouterr().err
    assert "--radius-mm" in err and "must be a finite positive number" in err


def test_force_columns_under_the_labs_own_names_are_mapped_with_the_option_the_error_names(tmp_path, capsys):
    p, eps, force = sarosi_data(4)
    path = tmp_path / "lab.csv"
    path.write_text("pressure_bar;contraction_mm;force_N\n" + "".join(
        f"{a:.5f};{400 * b:.5f};{c:.4f}\n".replace(".", ",") for a, b, c in zip(p, eps, force)))  # fmt: skip
    argv = ["identify", "force", str(path), "--model", "sarosi", "--rest-length-mm", "400", "--json"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--columns p=NAME,y=NAME,force=NAME" in err
    assert main([*argv, "--columns", "p=pressure_bar,y=contraction_mm,force=force_N"]) == 0
    fitted = json.loads(capsys.readouterr().out)
    assert fitted["rmse_n"] < 5.0
