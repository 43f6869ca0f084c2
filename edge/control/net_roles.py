"""Which feedforward runs: the roles a bundle can fill and the evaluators that fill them.

Roles (``[feedforward] role`` in the rig config overrides the default):

* ``table``: the inverse lookup table (rate-independent hysteresis inverse);
* ``table+correction``: the table plus the ONNX correction MLP (``pmactl train --model correction``);
* ``net``: the inverse LSTM-NARMAX over the table (:class:`edge.control.net_narmax.NetInverse`);
* ``net+correction``: the net plus the correction (the correction's ``feedforward_bar`` feature
  is then the net's output, not the table's it was trained on: prefer ``net`` unless the
  correction was trained with it).

Default: a net when the bundle holds one, else the table; plus the correction when the bundle
holds one. A role the bundle cannot fill is one :class:`~edge.errors.BundleError` line.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from edge.errors import BundleError
from edge.hysteresis.lut import CompiledModel, read_table

if TYPE_CHECKING:
    from edge.control.net_narmax import NetForward, NetInverse, StepNet
    from edge.control.net_state_space import StateSpaceForward

FEEDFORWARD_ROLES = ("table", "table+correction", "net", "net+correction")
FORWARD_ROLES = ("table", "net")


def feedforward_roles(has_inverse_net: bool, has_correction: bool) -> list[str]:
    """The feedforward roles a bundle with these parts can fill."""
    roles = ["table"] + (["table+correction"] if has_correction else [])
    if has_inverse_net:
        roles += ["net"] + (["net+correction"] if has_correction else [])
    return roles


def choose_role(available: list[str], wanted: str, source: str) -> str:
    """``wanted`` (empty: the default, see module docstring) checked against ``available``."""
    if not wanted:
        net = [r for r in available if r.startswith("net")]
        return (net or available)[-1]
    if wanted not in FEEDFORWARD_ROLES:
        known = ", ".join(FEEDFORWARD_ROLES)
        raise BundleError(f"{source}: [feedforward] role {wanted!r} unknown; choose one of {known}")
    if wanted not in available:
        raise BundleError(
            f"{source}: [feedforward] role {wanted!r} needs a part this bundle does not hold (it can fill "
            f"{', '.join(available)}); choose one of those, or train it "
            "(pmactl train --model lstm-narmax|hammerstein|state-space --save)"
        )
    return wanted


def ticks_per_step(step_s: float, period_s: float, where: Path) -> int:
    """Loop ticks per net step; refuses a net slower than the loop cannot divide, or faster than it."""
    ratio = step_s / period_s
    ticks = int(round(ratio))
    if not math.isfinite(ratio) or ticks < 1 or abs(ratio - ticks) > 1e-6 * max(1.0, ratio):
        raise BundleError(
            f"{where}: the net steps every {step_s * 1e3:g} ms, which is not a whole number of the loop's "
            f"{period_s * 1e3:g} ms ticks; set [loop] rate_hz to a multiple of {1.0 / step_s:g} Hz"
        )
    return ticks


def _spec_float(spec: Mapping[str, object], key: str, where: Path) -> float:
    value = spec.get(key)
    if not isinstance(value, int | float) or not math.isfinite(value):
        raise BundleError(f"{where}: the net entry has no numeric {key!r}; re-export the bundle")
    return float(value)


def step_net(path: Path, spec: Mapping[str, object]) -> StepNet:
    """The evaluator of a net step graph: Hammerstein or LSTM-NARMAX, told by its carried state."""
    from edge.control.net_hammerstein import HammersteinNet, is_hammerstein
    from edge.control.net_narmax import NarmaxNet

    return HammersteinNet(path, spec) if is_hammerstein(spec) else NarmaxNet(path, spec)


def net_inverse(path: Path, spec: Mapping[str, object], table: CompiledModel, period_s: float) -> NetInverse:
    """The net feedforward over ``table`` (the bundle's inverse table) at loop period ``period_s`` [s]."""
    from edge.control.net_narmax import NetInverse

    ticks = ticks_per_step(_spec_float(spec, "step_s", path), period_s, path)
    preview = spec.get("preview_s", 0.0)
    preview_s = float(preview) if isinstance(preview, int | float) and math.isfinite(preview) and preview >= 0 else -1.0
    if preview_s < 0:
        raise BundleError(f"{path}: the inverse net's preview_s {preview!r} is not a time >= 0; re-export the bundle")
    return NetInverse(step_net(path, spec), table, ticks, preview_s)


def net_forward(
    path: Path, spec: Mapping[str, object], release: Path, period_s: float
) -> NetForward | StateSpaceForward:
    """The net forward model (pressure [bar] -> contraction [mm]): with its operator table, or a
    state-space step graph (no operator, :mod:`edge.control.net_state_space`)."""
    from edge.control.net_narmax import NetForward
    from edge.control.net_state_space import StateSpaceForward, StateSpaceNet, is_state_space

    if is_state_space(spec):
        ticks = ticks_per_step(_spec_float(spec, "step_s", path), period_s, path)
        return StateSpaceForward(StateSpaceNet(path, spec), ticks)
    operator = spec.get("operator")
    if not isinstance(operator, Mapping) or not isinstance(operator.get("file"), str):
        raise BundleError(f"{path}: the forward net has no operator table entry; re-export the bundle")
    table = CompiledModel(read_table(release / str(operator["file"])))
    ticks = ticks_per_step(_spec_float(spec, "step_s", path), period_s, path)
    return NetForward(
        step_net(path, spec),
        table,
        ticks,
        _spec_float(operator, "warp_centre", path),
        _spec_float(operator, "warp_half_range", path),
    )
