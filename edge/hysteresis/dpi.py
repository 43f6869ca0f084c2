"""DPI: the digitized dual-operator Prandtl-Ishlinskii model (Zhou2022).

State: ``N`` fundamental operators ("digits") with a fill ``s_i`` in [0, 1]; ``s_i`` is the
paper's binary digit ``b_i`` when the input moves in whole steps, a fraction in between.
Each digit has an expansion pair ``(dXe_i, dYe_i)`` and a contraction pair ``(dXc_i, dYc_i)``
(stored as positive magnitudes). An input increase fills the least significant unfilled digit
first, moving the output by ``dYe_i / dXe_i`` per unit input; a decrease empties the least
significant filled digit first using the contraction pair. Between the all-empty state B0 at
``(x0, y0)`` and the all-full state B1 at ``(x1, y1)`` this is exactly the classical PI model
when both pairs are equal (``dX_i = 2 (r_{i+1} - r_i)``, ``dY_i = dX_i * (w_0 + ... + w_i)``,
``s_i = (z_i - z_{i+1}) / dX_i + 1/2`` in play outputs ``z``), which the tests check.

With unequal pairs, repeated cycles drift (Zhou2022 eqs 12-14). The turning-point compensator
(eqs 15-20) fixes it: at every reversal the remaining branch is scaled so that completing it
lands exactly on B1 (expansion) or B0 (contraction). The paper distributes the correction over
the digits in proportion to their ``dY`` (``f(i) = dY_i / sum dY``), i.e. a common scale factor;
we apply it per branch rather than accumulating it into the parameters, which is equivalent for
the branch and keeps the identified parameters unchanged. The same scaling is applied to the
input increments, so the model is symmetric in ``X`` and ``Y``: the inverse is the same model
with the pairs swapped (eqs 21-22), exact up to rounding.

Each branch is evaluated in closed form from its turning point (fills and output from the
turning point's state and the input travelled since it), so the output carries the roundings of
the current branch only, not one per tick of the whole history.

Conditioning. The forward and the inverse model evolve separately (two tables on the edge), so
the inverse sees the forward's output rounded to a double. A digit's fill is then known to the
inverse only to ``eps |y| / dY_i``, and at the next reversal that error enters the compensator
scale weighted by the digit's ``dY`` of the other direction. Each reversal can therefore
multiply the mismatch by up to ``max_i dYc_i / dYe_i`` (or its reciprocal); the forward model
has the same factor with ``dX`` (1 for identified models, whose digits have equal widths). This
is a property of the model, not of the arithmetic: evaluated in 80-digit arithmetic, the inverse
of a DPI fitted without an asymmetry bound to the shipped example data (floored digits of slope
0.148 whose other direction has slope 45 or 93: ratios 300 and 630) moves by 3e-6 bar when its
input moves by 1e-15 (relative), and its round trip reached 4e-6 bar. With per-digit ratios up
to 3 the round trip is exact to ~1e-13 of the range over thousands of reversals, whatever the
spread of slopes between digits; the identification therefore bounds the ratio (10 by default,
:class:`host.identify.dpi.DPIEstimator`), which gives ~2e-12 bar on the example data.
The bound makes a large amplification rare, not impossible: of 6200 random models within it
(equal widths, tests/test_dpi.py) the worst round trip over 3000 samples was 5.7e-6 of the
range, and that model, run for 300 000 samples, reached 8.6e-2 at isolated reversals.
Identified models (the two example records, six real muscle records) stay within 4e-11 over
100 000 samples; a bound of 3 keeps every draw at rounding (3.7e-13 over 30 000 samples) but
costs up to 2 % of p-p held-out on real records (S001P001: 13.1 vs 11.1 %), so it stays 10.
Fills within ``_SNAP`` (1e-10) of 0 or 1 are snapped: that resets the rounding-sized fill
mismatch a reversal at a digit boundary would otherwise amplify, and moves the output by at most
``1e-10 dY_i``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from edge.errors import ModelError
from edge.hysteresis.base import HysteresisModel, as_signal, check_range
from edge.hysteresis.table import LookupTable

_SNAP = 1e-10  # see the module docstring
_NEGLIGIBLE = 1e-9  # a remaining branch shorter than this share of the range needs no scaling


class DPIKernel:
    """Per-tick DPI evaluation on plain Python floats (shared by the model and its table).

    Each branch is evaluated in closed form from its turning point: the fills and the output
    follow from the turning point's fills and cursor and the input travelled since the turn,
    ``y = y_turn +/- by * sum_i |s_i - s_i,turn| dY_i``, instead of adding one increment per
    tick. The output then carries a few roundings of the current branch, not one per tick of
    the whole history (see the module docstring for why that matters to the inverse).
    """

    stage = "dpi"

    def __init__(self, arrays: dict[str, NDArray[np.float64]]) -> None:
        self._dxe = arrays["dxe"].tolist()
        self._dye = arrays["dye"].tolist()
        self._dxc = arrays["dxc"].tolist()
        self._dyc = arrays["dyc"].tolist()
        self._x0, self._y0, self._x1, self._y1 = arrays["anchors"].tolist()
        self._compensate = bool(arrays["compensate"])
        self._n = len(self._dxe)
        self.s: list[float] = arrays["fills"].tolist()
        self.x, self.y, direction, self.bx, self.by = arrays["cursor"].tolist()
        self.direction = int(direction)
        # the current branch's turning point; tables written before it was stored start a
        # branch where they stand, which is the same branch in exact arithmetic
        self.turn_s: list[float] = list(self.s)
        self.turn_x, self.turn_y = self.x, self.y
        if "turn_fills" in arrays:
            self.turn_s = arrays["turn_fills"].tolist()
            self.turn_x, self.turn_y = arrays["turn_cursor"].tolist()

    def arrays(self) -> dict[str, NDArray[np.float64]]:
        """Parameters and current state as arrays (the table form)."""
        return {
            "dxe": np.array(self._dxe),
            "dye": np.array(self._dye),
            "dxc": np.array(self._dxc),
            "dyc": np.array(self._dyc),
            "anchors": np.array([self._x0, self._y0, self._x1, self._y1]),
            "compensate": np.array(float(self._compensate)),
            "fills": np.array(self.s),
            "cursor": np.array([self.x, self.y, self.direction, self.bx, self.by]),
            "turn_fills": np.array(self.turn_s),
            "turn_cursor": np.array([self.turn_x, self.turn_y]),
        }

    def mark_turn(self) -> None:
        """Make the current state the turning point the branch is evaluated from."""
        self.turn_s[:] = self.s
        self.turn_x, self.turn_y = self.x, self.y

    def _turn(self, direction: int) -> None:
        """Start a branch: compute the compensator scales (Zhou2022 eqs 15-20)."""
        self.mark_turn()
        self.direction = direction
        self.bx = self.by = 1.0
        if not self._compensate:
            return
        s = self.s
        # Near B0/B1 both the remaining room and the distance to the anchor are rounding-sized
        # and their ratio is noise: a forward model and its inverse would then scale the branch
        # differently. Such a branch is negligible, so it is left unscaled.
        if direction > 0:
            rx = sum((1.0 - f) * d for f, d in zip(s, self._dxe))
            ry = sum((1.0 - f) * d for f, d in zip(s, self._dye))
            if rx > _NEGLIGIBLE * (self._x1 - self._x0) and ry > _NEGLIGIBLE * (self._y1 - self._y0):
                self.bx = (self._x1 - self.x) / rx
                self.by = (self._y1 - self.y) / ry
        else:
            rx = sum(f * d for f, d in zip(s, self._dxc))
            ry = sum(f * d for f, d in zip(s, self._dyc))
            if rx > _NEGLIGIBLE * (self._x1 - self._x0) and ry > _NEGLIGIBLE * (self._y1 - self._y0):
                self.bx = (self.x - self._x0) / rx
                self.by = (self.y - self._y0) / ry

    def _expand(self, x: float) -> None:
        """Fill from the turning point by the input travelled since it (``x - turn_x``)."""
        start_s, s, dxe, dye, bx = self.turn_s, self.s, self._dxe, self._dye, self.bx
        left = x - self.turn_x
        gained = 0.0  # sum of (fill gained) * dYe over the digits
        for i in range(self._n):
            start = start_s[i]
            if start >= 1.0:
                continue
            width = dxe[i] * bx
            room = (1.0 - start) * width
            if left < room:
                frac = left / width
                if start + frac < 1.0 - _SNAP:
                    s[i] = start + frac
                    gained += frac * dye[i]
                else:
                    s[i] = 1.0
                    gained += (1.0 - start) * dye[i]
                break
            s[i] = 1.0
            gained += (1.0 - start) * dye[i]
            left -= room
        self.y = self.turn_y + gained * self.by

    def _contract(self, x: float) -> None:
        """Empty from the turning point by the input travelled since it (``turn_x - x``)."""
        start_s, s, dxc, dyc, bx = self.turn_s, self.s, self._dxc, self._dyc, self.bx
        left = self.turn_x - x
        lost = 0.0  # sum of (fill lost) * dYc over the digits
        for i in range(self._n):
            start = start_s[i]
            if start <= 0.0:
                continue
            width = dxc[i] * bx
            room = start * width
            if left < room:
                frac = left / width
                if start - frac > _SNAP:
                    s[i] = start - frac
                    lost += frac * dyc[i]
                else:
                    s[i] = 0.0
                    lost += start * dyc[i]
                break
            s[i] = 0.0
            lost += start * dyc[i]
            left -= room
        self.y = self.turn_y - lost * self.by

    def step(self, x: float) -> float:
        dx = x - self.x
        if dx > 0.0:
            if self.direction != 1:
                self._turn(1)
            self._expand(x)
        elif dx < 0.0:
            if self.direction != -1:
                self._turn(-1)
            self._contract(x)
        self.x = x
        return self.y


class DPIModel(HysteresisModel):
    """DPI model (see module docstring).

    Args:
        dxe, dye: expansion pairs, positive (input / output units).
        dxc, dyc: contraction pairs, positive magnitudes.
        x0, y0: input and output at B0 (all digits empty).
        x1, y1: input and output at B1 (all full); default ``x0 + sum(dxe)``, ``y0 + sum(dye)``.
        compensate: apply the turning-point compensator (default on; off only to study drift).

    Inputs are clamped to ``[x0, x1]``.
    """

    kind = "dpi"

    def __init__(
        self,
        dxe: ArrayLike,
        dye: ArrayLike,
        dxc: ArrayLike,
        dyc: ArrayLike,
        *,
        x0: float,
        y0: float,
        x1: float | None = None,
        y1: float | None = None,
        compensate: bool = True,
    ) -> None:
        pairs = [as_signal(a, name) for a, name in ((dxe, "dxe"), (dye, "dye"), (dxc, "dxc"), (dyc, "dyc"))]
        n = pairs[0].size
        if n == 0 or any(p.size != n for p in pairs):
            raise ModelError("DPI needs four pair arrays of the same non-zero length")
        for p, name in zip(pairs, ("dxe", "dye", "dxc", "dyc")):
            if np.any(p <= 0):
                raise ModelError(
                    f"DPI {name} must be > 0 everywhere (monotone branches); "
                    f"smallest is {p.min():.3g}: give the fit a positive lower bound"
                )
        x1 = x0 + float(pairs[0].sum()) if x1 is None else x1
        y1 = y0 + float(pairs[1].sum()) if y1 is None else y1
        check_range(x0, x1, "DPI input range (x0, x1)")
        check_range(y0, y1, "DPI output range (y0, y1)")
        self.params = dict(zip(("dxe", "dye", "dxc", "dyc"), pairs))
        self.anchors = (float(x0), float(y0), float(x1), float(y1))
        self.compensate = compensate
        self._kernel = DPIKernel(
            {
                **self.params,
                "anchors": np.array(self.anchors),
                "compensate": np.array(float(compensate)),
                "fills": np.zeros(n),
                "cursor": np.array([x0, y0, 0.0, 1.0, 1.0]),
            }
        )
        self.reset(x0, "ascending")

    @property
    def n_operators(self) -> int:
        return self.params["dxe"].size

    @property
    def input_range(self) -> tuple[float, float]:
        return self.anchors[0], self.anchors[2]

    def step(self, u: float) -> float:
        return self._kernel.step(self._clamp(float(u)))

    def _saturate(self, positive: bool) -> None:
        x0, y0, x1, y1 = self.anchors
        k = self._kernel
        k.direction, k.bx, k.by = 0, 1.0, 1.0
        k.s = [1.0 if positive else 0.0] * self.n_operators
        k.x, k.y = (x1, y1) if positive else (x0, y0)
        k.mark_turn()

    def get_state(self) -> dict[str, NDArray[np.float64]]:
        arrays = self._kernel.arrays()
        return {key: arrays[key] for key in ("fills", "cursor", "turn_fills", "turn_cursor")}

    def set_state(self, state: dict[str, NDArray[np.float64]]) -> None:
        """Restore a state; one without the turning point (``turn_*``) starts a branch where it stands."""
        fills = np.asarray(state["fills"], dtype=float)
        turn_fills = np.asarray(state.get("turn_fills", fills), dtype=float)
        if fills.size != self.n_operators or turn_fills.size != self.n_operators:
            raise ModelError(f"DPI state has {fills.size} digits; this model has {self.n_operators}")
        k = self._kernel
        k.s = fills.tolist()
        k.x, k.y, direction, k.bx, k.by = np.asarray(state["cursor"], dtype=float).tolist()
        k.direction = int(direction)
        k.turn_s = turn_fills.tolist()
        k.turn_x, k.turn_y = np.asarray(state.get("turn_cursor", [k.x, k.y]), dtype=float).tolist()

    def inverse(self) -> DPIModel:
        """Swap the X and Y of every pair and of the anchors (Zhou2022 eqs 21-22)."""
        p = self.params
        x0, y0, x1, y1 = self.anchors
        model = DPIModel(
            p["dye"],
            p["dxe"],
            p["dyc"],
            p["dxc"],
            x0=y0,
            y0=x0,
            x1=y1,
            y1=x1,
            compensate=self.compensate,
        )
        model.set_state(swap_state(self.get_state()))
        return model

    def compile(self) -> LookupTable:
        return LookupTable.chain(self.kind, [(DPIKernel.stage, self._kernel.arrays())], self.input_range)


def swap_state(state: dict[str, NDArray[np.float64]]) -> dict[str, NDArray[np.float64]]:
    """The inverse model's state for a forward state: same fills, X and Y exchanged."""
    x, y, direction, bx, by = np.asarray(state["cursor"], dtype=float).tolist()
    swapped = {"fills": np.array(state["fills"], dtype=float), "cursor": np.array([y, x, direction, by, bx])}
    if "turn_cursor" in state:
        turn_x, turn_y = np.asarray(state["turn_cursor"], dtype=float).tolist()
        swapped["turn_fills"] = np.array(state["turn_fills"], dtype=float)
        swapped["turn_cursor"] = np.array([turn_y, turn_x])
    return swapped
