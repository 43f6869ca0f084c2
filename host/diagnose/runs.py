"""Several runs of one rig as one data set: concatenated samples, a run label per sample.

Each run may restart ``t`` at 0 and be short (one inflate/deflate cycle). Signals that carry
memory (Preisach rows, low-pass filters) are computed per run, each starting from its own first
sample; the Everett grid is shared (one hysteresis for the rig). A load or temperature column
constant within each run and different between runs is a column like any other.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError
from host.data import Measurement
from host.identify.common import MemoryStart, memory_start
from host.identify.preisach import EverettGrid, regressor_chunks

COLUMNS = ("load", "temperature")


@dataclass
class RunSet:
    """Samples of one or more runs, concatenated in the order given."""

    t: NDArray[np.float64]  # time within its run [s]
    clock: NDArray[np.float64]  # time since the first run started, runs laid end to end [s]
    u: NDArray[np.float64]
    y: NDArray[np.float64]
    run: NDArray[np.int64]  # run index per sample
    dt: float  # sample period [s] (the runs' median)
    names: list[str]
    columns: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    # ``u`` is the recorded input through this actuator lag [s] (negative: its inverse;
    # :mod:`host.diagnose.actuator`); 0: as recorded
    input_lag_s: float = 0.0

    @property
    def n_runs(self) -> int:
        return len(self.names)

    def bounds(self) -> list[tuple[int, int]]:
        """(first, stop) sample index of each run."""
        edges = np.flatnonzero(np.diff(self.run)) + 1
        starts = np.r_[0, edges]
        stops = np.r_[edges, self.run.size]
        return [(int(a), int(b)) for a, b in zip(starts, stops)]

    def per_run(
        self, fn: Callable[[NDArray[np.float64]], NDArray[np.float64]], values: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """``fn`` applied to each run's slice of ``values`` (memory restarts at each run)."""
        out = np.empty_like(values, dtype=np.float64)
        for a, b in self.bounds():
            out[a:b] = fn(values[a:b])
        return out


def _decimate(m: Measurement, q: int) -> Measurement:
    if q <= 1:
        return m
    n = len(m) // q * q

    def mean(v: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(v[:n].reshape(-1, q).mean(axis=1), dtype=np.float64)

    return Measurement(m.t[:n:q].copy(), mean(m.u), mean(m.y), {k: mean(v) for k, v in m.extras.items()}, m.source)


def _resampled(m: Measurement, dt: float) -> Measurement:
    """``m`` on a uniform grid of step ``dt`` [s] from its first sample (linear interpolation)."""
    if abs(m.dt - dt) <= 0.01 * dt:
        return m
    t = m.t[0] + np.arange(int(np.floor((m.t[-1] - m.t[0]) / dt)) + 1) * dt
    return Measurement(
        t,
        np.interp(t, m.t, m.u),
        np.interp(t, m.t, m.y),
        {k: np.interp(t, m.t, v) for k, v in m.extras.items()},
        m.source,
    )


def run_set(runs: list[Measurement], max_rows: int, min_samples: int) -> RunSet:
    """The runs as one :class:`RunSet`, decimated (block means) when together they exceed
    ``max_rows``. A column is kept only when every run has it. Bad input: one :class:`DataError`."""
    if not runs:
        raise DataError("no runs given; name one or more CSV files")
    total = sum(len(m) for m in runs)
    if total < min_samples:
        raise DataError(f"{total} samples in all is too short to diagnose; record at least {min_samples}")
    q = int(np.ceil(total / max_rows))
    notes = []
    if q > 1:
        notes.append(
            f"{total} samples decimated by {q} (block means) to about {total // q}; dead times shorter than "
            f"{3 * q * float(np.median([m.dt for m in runs])):.3g} s cannot be resolved"
        )
        runs = [_decimate(m, q) for m in runs]
    dts = np.array([m.dt for m in runs])
    dt = float(dts.max())
    if np.any(np.abs(dts - dt) > 0.01 * dt):
        notes.append(
            f"runs sampled at {1 / dts.max():.3g}-{1 / dts.min():.3g} Hz were resampled (linear interpolation) to the "
            f"slowest rate, {1 / dt:.3g} Hz, so that one noise model and one set of lags fits them all"
        )
        runs = [_resampled(m, dt) for m in runs]
    present = [c for c in COLUMNS if all(c in m.extras for m in runs)]
    missing = [c for c in COLUMNS if any(c in m.extras for m in runs) and c not in present]
    for c in missing:
        notes.append(f"the {c!r} column is in some runs only, so it is not tested; record it in every run")
    clock, offset = [], 0.0
    for m in runs:
        clock.append(m.t - m.t[0] + offset)
        offset = float(clock[-1][-1]) + dt
    for m in runs:
        if np.ptp(m.y) <= 1e-12 * max(1.0, float(np.abs(m.y).max())) and len(runs) == 1:
            raise DataError(
                f"{m.source}: the output y is constant ({m.y[0]:g}); check the sensor wiring or the column mapping"
            )
    u = np.concatenate([m.u for m in runs])
    if np.ptp(u) <= 1e-9 * max(1.0, float(np.abs(u).max())):
        raise DataError("the input u is constant in every run; a diagnosis needs the actuator to move")
    return RunSet(
        t=np.concatenate([m.t - m.t[0] for m in runs]),
        clock=np.concatenate(clock),
        u=u,
        y=np.concatenate([m.y for m in runs]),
        run=np.concatenate([np.full(len(m), i, dtype=np.int64) for i, m in enumerate(runs)]),
        dt=dt,
        names=[m.source for m in runs],
        columns={c: np.concatenate([m.extras[c] for m in runs]) for c in present},
        notes=notes,
    )


def node_differences(levels: int) -> NDArray[np.float64]:
    """First differences between neighbouring Everett nodes (one row per neighbouring pair), for a
    smoothness penalty: nodes no training row visits take their neighbours' values instead of 0."""
    grid = EverettGrid(0.0, 1.0, levels)
    pairs = []
    for j, k in zip(grid.rows, grid.cols):
        if j + 1 <= levels:
            pairs.append((grid.flat[j, k], grid.flat[j + 1, k]))
        if k + 1 < j:
            pairs.append((grid.flat[j, k], grid.flat[j, k + 1]))
    d = np.zeros((len(pairs), grid.size))
    for row, (a, b) in enumerate(pairs):
        d[row, a], d[row, b] = 1.0, -1.0
    return d


def _known_start(u: NDArray[np.float64], lo: float, hi: float) -> MemoryStart | None:
    """Where a run's memory is known on a grid ending at [``lo``, ``hi``]: its first visit to an end
    of the range when that comes before its middle, else None (unknown)."""
    found = memory_start(u)
    at_end = min(abs(float(u[found.index]) - lo), abs(float(u[found.index]) - hi)) <= 0.005 * (hi - lo)
    return found if at_end and found.index < u.size // 2 else None


def preisach_basis(
    rs: RunSet, levels: int, pad_levels: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], list[str]]:
    """(nodes, smoothness, notes): :func:`preisach_nodes` on ``levels`` intervals padded by
    ``pad_levels`` each side, and the first-difference penalty D^T D of that same grid
    (:func:`node_differences`), so the two always describe one grid."""
    nodes, notes = preisach_nodes(rs, levels, pad_levels)
    d = node_differences(levels + 2 * pad_levels)
    return nodes, d.T @ d, notes


def preisach_nodes(rs: RunSet, levels: int, pad_levels: int = 0) -> tuple[NDArray[np.float64], list[str]]:
    """Preisach regressor rows (Everett nodes on one grid over every run's input), each run from
    its own first sample: from where the memory is known when the run reaches an end of the
    range before its middle, else with the state assumed (the input rose from the range's minimum;
    a note says so).

    ``pad_levels`` > 0 extends the grid by that many intervals (of the input range over
    ``levels``) below and above the input's range, ``levels + 2 pad_levels`` in all: relays that
    switch outside the range keep their state when the input reaches its minimum or maximum, so a
    loop that does not close at the ends of the range (a play operator, a Bouc-Wen or friction
    element wider than the excursion) is in the class. The input's extremes then erase nothing,
    and every run starts as if it had risen from the grid's minimum (a rested muscle)."""
    lo, hi = float(rs.u.min()), float(rs.u.max())
    step = (hi - lo) / levels
    grid = EverettGrid(lo - pad_levels * step, hi + pad_levels * step, levels + 2 * pad_levels)
    rows = np.zeros((rs.u.size, grid.size))
    assumed = 0
    for a, b in rs.bounds():
        u = rs.u[a:b]
        known = None if pad_levels else _known_start(u, lo, hi)
        assumed += not pad_levels and known is None
        begin = known or MemoryStart(0, "ascending")  # unknown or padded: risen from the grid's minimum
        block_rows = np.zeros((b - a, grid.size))
        offset = begin.index
        for block in regressor_chunks(u, grid, begin, capacity=128):
            block_rows[offset : offset + len(block)] = block
            offset += len(block)
        block_rows[: begin.index] = block_rows[begin.index]  # before the memory is known: its first known row
        rows[a:b] = block_rows
    notes = []
    if assumed:
        notes.append(
            f"{assumed} of {rs.n_runs} run(s) never reach an end of the input range in their first half, so their "
            "hysteresis state at the start is assumed (the input rose from the range's minimum)"
        )
    return rows, notes
