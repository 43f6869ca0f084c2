"""Several runs diagnosed together must share their units: mixed units are one line, exit 2."""

from __future__ import annotations

import numpy as np

from host.cli import main


def test_runs_in_different_units_are_refused_in_one_line(tmp_path, capsys):
    t = np.arange(300) * 0.02
    u = 2.0 + 2.0 * np.sin(t)
    for name, unit, scale in (("a.csv", "mm", 1.0), ("b.csv", "m", 1e-3)):
        y = scale * 10.0 * np.sin(t - 0.2)
        np.savetxt(tmp_path / name, np.c_[t, u, y], delimiter=",", header=f"t,u [bar],y [{unit}]", comments="")
    assert main(["diagnose", str(tmp_path / "a.csv"), str(tmp_path / "b.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "mixed units of y: a.csv is in mm, b.csv in m" in err[0], err
