"""Maxwell-slip friction (PAMInertial sec 2.3): presliding hysteresis as N elastoplastic elements.

Element ``i`` is a spring of stiffness ``k_i`` [N per unit of position] whose stretch ``s_i`` slips
once its force reaches the break force ``f_i`` [N]: with ``D_i = f_i / k_i`` the slip displacement,
``s_i <- clip(s_i + dx, -D_i, D_i)`` and the element pushes ``k_i s_i``. The model is

    F(x) = F0 + k0 x + sum_i k_i s_i(x),

``F0`` [N] an offset (the pressure force on a cylinder), ``k0`` [N/unit] a linear elastic term. For
fixed slip displacements the force is linear in ``k_0..k_N``, so they are fitted by
non-negative least squares (every element a physical spring) and the ``D_i`` are searched over
geometric grids between a small fraction and half of the position's range, then refined. Elements start
unstretched at the first sample; the first 5 % of a record is not scored while the memory fills.

The number of elements is chosen on held-out data: the fit is made on the first 70 % of the
record and scored on the last 30 % (a block in time, as a user would validate), and the
smallest N whose held-out RMSE is within 2 % of the best is kept (parsimony), then refitted on all.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Self

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize, nnls

from edge.errors import DataError

Array = NDArray[np.float64]
WARMUP = 0.05
TRAIN_SHARE = 0.7


def slip_stretches(x: Array, slip: Array) -> Array:
    """Stretch of each element (columns) along the position path ``x`` (rows), starting unstretched."""
    out = np.empty((x.size, slip.size))
    s = np.zeros(slip.size)
    previous = x[0]
    for i, value in enumerate(x.tolist()):
        s = np.clip(s + (value - previous), -slip, slip)
        out[i] = s
        previous = value
    return out


class MaxwellSlip:
    """N-element Maxwell-slip model (module docstring), fitted by NNLS over slip-displacement grids.

    Args:
        elements: number of elastoplastic elements N (>= 1).
        refine: after the grid, refine the slip displacements by Nelder-Mead on log D (the springs
            re-solved by NNLS at every step); the held-out scan over N uses the grid alone.

    Learned: ``slip_`` (D_i, position units), ``stiffness_`` (k_i, N per position unit),
    ``break_force_`` (f_i = k_i D_i, N), ``linear_stiffness_`` (k0), ``offset_`` (F0, N).
    """

    def __init__(self, elements: int = 4, refine: bool = False) -> None:
        self.elements = elements
        self.refine = refine

    def _design(self, x: Array, slip: Array) -> Array:
        return np.column_stack([np.ones_like(x), x - x[0], slip_stretches(x, slip)])

    def _solve(self, x: Array, f: Array, mask: Array, slip: Array) -> tuple[float, Array]:
        """NNLS on the springs for fixed slips (offset and linear term free in sign): cost, coefficients."""
        design = self._design(x, slip)[mask]
        shift = float(f[mask].min())
        augmented = np.column_stack([design[:, :1], -design[:, :1], design[:, 1:], -design[:, 1:2]])
        coef, _ = nnls(augmented, f[mask] - shift)
        full = np.concatenate([[coef[0] - coef[1] + shift, coef[2] - coef[-1]], coef[3:-1]])
        return float(np.sum((design @ full - f[mask]) ** 2)), full

    def fit(self, position: ArrayLike, force: ArrayLike, fit_mask: Array | None = None) -> Self:
        """Fit to the samples in ``fit_mask`` (default: all after the warm-up); the memory runs over all."""
        x, f = np.asarray(position, float), np.asarray(force, float)
        if self.elements < 1:
            raise DataError(f"--elements {self.elements} must be at least 1")
        if x.size != f.size or x.size < 20 or np.ptp(x) <= 0:
            raise DataError("position and force need the same length, at least 20 samples, and a moving position")
        mask = np.ones(x.size, bool) if fit_mask is None else fit_mask.copy()
        mask[: int(WARMUP * x.size)] = False
        span = float(np.ptp(x))
        best: tuple[float, Array, Array] | None = None
        for low in (0.002, 0.01, 0.03):
            for high in (0.05, 0.2, 0.5):
                slip = (
                    np.geomspace(low * span, high * span, self.elements)
                    if self.elements > 1
                    else np.array([3 * low * span])
                )
                cost, coef = self._solve(x, f, mask, slip)
                if best is None or cost < best[0]:
                    best = (cost, slip, coef)
        assert best is not None
        if self.refine:
            result = minimize(
                lambda log_slip: self._solve(x, f, mask, np.exp(log_slip))[0],
                np.log(best[1]),
                method="Nelder-Mead",
                options={"maxfev": 60 * self.elements, "xatol": 1e-3, "fatol": 1e-9},
            )
            slip = np.sort(np.exp(result.x))
            cost, coef = self._solve(x, f, mask, slip)
            if cost < best[0]:
                best = (cost, slip, coef)
        assert best is not None
        _, slip, coef = best
        self.slip_ = slip
        self.offset_, self.linear_stiffness_ = float(coef[0]), float(coef[1])
        self.stiffness_ = coef[2:]
        self.break_force_ = self.stiffness_ * slip
        self.x0_ = float(x[0])
        return self

    def predict(self, position: ArrayLike) -> Array:
        """Force [N] along ``position``, elements unstretched at its first sample."""
        x = np.asarray(position, float)
        coef = np.concatenate([[self.offset_, self.linear_stiffness_], self.stiffness_])
        design = np.column_stack([np.ones_like(x), x - x[0], slip_stretches(x, self.slip_)])
        return np.asarray(design @ coef, dtype=np.float64)

    def get_params(self) -> dict[str, object]:
        return {"elements": self.elements, "refine": self.refine}


@dataclass
class SlipSelection:
    """The chosen model, its scores (RMSE [N] and % of the force range) and the scan over N."""

    model: MaxwellSlip
    train_rmse: float
    train_rmse_pct: float
    test_rmse: float
    test_rmse_pct: float
    note: str
    scan: list[dict[str, float]] = field(default_factory=list)

    def as_dict(self) -> dict[str, object]:
        return {
            "elements": self.model.elements,
            "stiffness": self.model.stiffness_.tolist(),
            "break_force_n": self.model.break_force_.tolist(),
            "slip_displacement": self.model.slip_.tolist(),
            "linear_stiffness": self.model.linear_stiffness_,
            "offset_n": self.model.offset_,
            "train_rmse_n": self.train_rmse,
            "train_rmse_pct_range": self.train_rmse_pct,
            "heldout_rmse_n": self.test_rmse,
            "heldout_rmse_pct_range": self.test_rmse_pct,
            "scan": self.scan,
            "note": self.note,
        }


def despike(position: Array) -> Array:
    """Median of three: removes single-sample position glitches (a laser's dropouts), keeps ramps and turns.

    A presliding model reacts to every reversal of its input, so one glitch of a few tenths of a
    millimetre flips every element with a smaller slip displacement (seen on the real O-ring run).
    """
    x = np.asarray(position, float)
    if x.size < 3:
        return x.copy()
    out = x.copy()
    out[1:-1] = np.median(np.column_stack([x[:-2], x[1:-1], x[2:]]), axis=1)
    return out


def _rmse(a: Array, b: Array) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)))


def select_and_fit(
    position: ArrayLike, force: ArrayLike, elements: int | None = None, max_elements: int = 8, clean: bool = True
) -> SlipSelection:
    """Choose N on the held-out last 30 % (unless given), refit on all; scores as in the module docstring.

    With ``clean`` the position goes through :func:`despike` first; the model then expects a
    despiked position too (``model.predict(despike(x))``).
    """
    if elements is not None and elements < 1:
        raise DataError(f"--elements {elements} must be at least 1")
    x, f = np.asarray(position, float), np.asarray(force, float)
    if clean:
        x = despike(x)
    spread = float(np.ptp(f)) or 1.0
    cut = int(TRAIN_SHARE * x.size)
    train = np.zeros(x.size, bool)
    train[:cut] = True
    candidates = [elements] if elements else list(range(1, max_elements + 1))
    scan = []
    for n in candidates:
        model = MaxwellSlip(n).fit(x, f, train)
        test_rmse = _rmse(model.predict(x)[cut:], f[cut:])
        scan.append({"elements": n, "test_rmse": test_rmse, "test_rmse_pct": 100 * test_rmse / spread})
    best = min(row["test_rmse"] for row in scan)
    chosen = next(row for row in scan if row["test_rmse"] <= 1.02 * best)
    n = int(chosen["elements"])
    held = MaxwellSlip(n).fit(x, f, train)
    final = MaxwellSlip(n).fit(x, f)
    start = int(WARMUP * x.size)
    train_rmse = _rmse(final.predict(x)[start:], f[start:])
    note = (
        f"N = {n} of {candidates[0]}..{candidates[-1]} chosen on the last {1 - TRAIN_SHARE:.0%} held out "
        "(smallest within 2 % of the best held-out RMSE); parameters refitted on the whole record"
        if not elements
        else f"N = {n} given; held-out score from a fit on the first {TRAIN_SHARE:.0%}"
    )
    test_rmse = _rmse(held.predict(x)[cut:], f[cut:])
    return SlipSelection(final, train_rmse, 100 * train_rmse / spread, test_rmse, 100 * test_rmse / spread, note, scan)


def plot_loops(records: list[tuple[str, Array, Array, MaxwellSlip]], path: str) -> None:
    """Measured vs fitted force-position loops, one panel per record, written to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(records), figsize=(5.5 * len(records), 4.2), squeeze=False)
    for ax, (name, x, f, model) in zip(axes[0], records):
        ax.plot(x, f, color="0.6", lw=0.8, label="measured")
        ax.plot(x, model.predict(x), color="C3", lw=0.9, label=f"Maxwell-slip, N = {model.elements}")
        ax.set_title(name)
        ax.set_xlabel("position")
        ax.set_ylabel("force [N]")
        ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
