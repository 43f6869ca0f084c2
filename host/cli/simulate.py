"""``pmactl simulate BUNDLE DATA.csv --out PRED.csv``: a saved model's forward model over an input.

Writes ``t, u, y_model`` (and ``y`` when the input file has it) so any protocol can score a
pmactl model (MATLAB's ``sim``/``compare``, SysIdentPy's ``predict``). The input may be a
recording (``t,u,y``) or a designed input (``t,u``). The start is ``--initial``: ``rest``,
``ascending``, ``descending`` (see :mod:`host.forward`) or ``estimate`` (needs ``y``: the start
whose output fits the record's calibration window best, as ``pmactl fit --test`` chooses it).
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError
from host.cli.lazy import lazy
from host.cli.options import add_data_options
from host.cli.outputs import OutputPathError, check_output

CALIBRATION_FRACTION = 0.1  # share of the record after the input moves, as pmactl fit --test
SAMPLE_PERIOD_RTOL = 0.01  # a net's input may be sampled this much off its step (clock jitter of a recording)


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg,unused-ignore]
    """Add ``pmactl simulate`` to the command line."""
    simulate = sub.add_parser("simulate", help="run a saved model's forward model (table or net) over an input CSV")
    simulate.add_argument("bundle", metavar="BUNDLE", help="folder written by pmactl fit --save or pmactl train --save")
    simulate.add_argument("data", metavar="DATA.csv", help="input: t [s], u (and y, if measured)")
    simulate.add_argument("--out", required=True, metavar="PRED.csv", help="new CSV: t, u, y_model (and y)")
    simulate.add_argument(
        "--initial",
        choices=["rest", "ascending", "descending", "estimate"],
        default="rest",
        help="start state: rest (as compiled), the ascending or descending outer branch at u[0], or estimate "
        "(needs y: the start that fits the first 10%% after the input moves best)",
    )
    simulate.add_argument(
        "--role",
        choices=["table", "net"],
        help="which forward model of a bundle: the lookup table or the forward net (default: the net when the "
        "bundle holds one; a net steps once per input sample, so the input must be sampled at its step)",
    )
    add_data_options(simulate, units=False)
    simulate.set_defaults(run=lazy("host.cli.simulate"))


def read_input(
    path: Path, args: argparse.Namespace
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64] | None]:
    """``t, u`` and ``y`` (``None`` when the file has no y column) of a CSV; one clear error otherwise.

    A recording and a designed input (``t, u`` alone: its rows are kept as spaced) are read as every
    measurement is (:func:`host.data.load_measurement`: delimiter, decimal comma, ``--columns``,
    ``--time-unit``, a time column that looks like milliseconds, values beyond 1e100)."""
    from host.cli.options import read_options
    from host.data import load_measurement

    m = load_measurement(path, options=read_options(args), min_samples=2, require_output=False)
    has_output = not np.all(np.isnan(m.y))  # a y column with a NaN is refused by the loader
    return m.t, m.u, (m.y if has_output else None)


def run(args: argparse.Namespace) -> int:
    from host.evaluate import calibration_window
    from host.forward import INITIAL_STATES, load_forward

    data, out = Path(args.data), Path(args.out)
    check_output(out, "--out", kind="file")
    if out.exists():
        raise OutputPathError(f"--out {out}: already exists; choose a new file name or move the old one away first")
    t, u, y = read_input(data, args)
    if args.initial == "estimate" and y is None:
        raise DataError(
            f"{data}: --initial estimate needs a measured y column; give --initial rest, ascending or descending"
        )
    model = load_forward(args.bundle, args.role)
    step_s = getattr(model, "step_s", None)
    if step_s is not None and u.size > 1:
        dt = float(np.median(np.diff(t)))
        if abs(dt - step_s) > SAMPLE_PERIOD_RTOL * step_s:
            raise DataError(
                f"{data}: sampled every {dt * 1e3:.4g} ms, the bundle's forward net steps every {step_s * 1e3:.4g} "
                "ms; resample the input to that step, or give --role table"
            )
    if args.initial == "estimate":
        assert y is not None
        start, end = calibration_window(u, CALIBRATION_FRACTION)
        fits = {}
        for state in INITIAL_STATES:
            prediction = model.run(u, state)
            fits[state] = (float(np.sqrt(np.mean((prediction[start:end] - y[start:end]) ** 2))), prediction)
        initial = min(fits, key=lambda s: fits[s][0])
        y_model = fits[initial][1]
        how = f"estimated on samples {start}-{end - 1} (window RMSE {fits[initial][0]:.4g})"
    else:
        initial, how = args.initial, "as asked"
        y_model = model.run(u, initial)
    columns = [t, u, y_model] + ([y] if y is not None else [])
    names = "t,u,y_model" + (",y" if y is not None else "")
    handle, scratch = tempfile.mkstemp(prefix=".pmactl-simulate-", suffix=".csv", dir=out.parent)
    os.close(handle)
    try:
        np.savetxt(scratch, np.column_stack(columns), delimiter=",", header=names, comments="", fmt="%.9g")
        os.replace(scratch, out)  # whole or nothing: a crash never leaves half a file under the name
    finally:
        Path(scratch).unlink(missing_ok=True)
    summary = f"{model.description} via {model.evaluator}, from {initial} ({how}): {u.size} samples -> {out}"
    if y is not None:
        rmse = float(np.sqrt(np.mean((y_model - y) ** 2)))
        summary += f"; RMSE against y {rmse:.4g} ({100 * rmse / float(np.ptp(y)):.2f} % p-p, no offset fitted)"
    print(summary)
    return 0
