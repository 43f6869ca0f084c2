"""The real base records of the injected scoring set, read from ``../shared/data`` (never copied).

Five piezo runs (dSPACE, 10 kHz; y in um) become 1 kHz records by block means of
:data:`PIEZO_BLOCK` samples. Five pneumatic-muscle records (y in mm) are several single-cycle logs
of ONE date joined in name order with time made continuous (each log starts one median step after
the previous one ends), kept on their own non-uniform time until :func:`coarsen` puts them on a
uniform grid at the median step. The data README describes the sources.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
PIEZO_BLOCK = 10  # 10 kHz -> 1 kHz


@dataclass(frozen=True)
class BaseRecord:
    """One real record: files ``first..last`` (by name) of one folder, joined in name order."""

    key: str
    kind: str  # "piezo" or "muscle"
    folder: str
    first: str
    last: str
    tau_range_s: tuple[float, float]  # creep time constants
    rate_lowpass_s: float  # low-pass of du/dt (quantised input)
    min_delay_s: float  # the shortest transport delay injected


def _piezo(name: str) -> BaseRecord:
    return BaseRecord(name, "piezo", "piezo_dspace", f"{name}.csv", f"{name}.csv", (0.05, 2.0), 0.005, 0.0005)


def _muscle(key: str, folder: str, first: str, last: str) -> BaseRecord:
    return BaseRecord(key, "muscle", f"pam_muscle_sensory/{folder}", first, last, (1.0, 30.0), 0.1, 0.02)


BASES = (
    _piezo("20_hz_no_lp"),
    _piezo("bigsine_1"),
    _piezo("prbn_1"),
    _piezo("sine100_1"),
    _piezo("tri50_1"),
    _muscle("18-03_S001-S007", "18-03-2026_Length_Characterisation", "S001P001.csv", "S007P003.csv"),
    _muscle("31-03_S011-S019", "31-03-2026_Length_Characterisation", "S011P001.csv", "S019P003.csv"),
    _muscle("07-17_all", "2026-07-17_Literature_Comparison", "S001P001.csv", "S012P002.csv"),
    _muscle("07-21_all", "2026-07-21_Literature_Comparison", "S013P001.csv", "S015P002.csv"),
    _muscle("07-22_all", "2026-07-22_Literature_Comparison", "S016P001.csv", "S021P002.csv"),
)
BY_KEY = {b.key: b for b in BASES}


def record_paths(data_root: Path, base: BaseRecord) -> list[Path]:
    """The files of ``base`` under ``data_root``, in name order (empty when absent)."""
    folder = data_root / base.folder
    return sorted(p for p in folder.glob("*.csv") if base.first <= p.name <= base.last)


@functools.lru_cache(maxsize=12)
def native_record(data_root: str, key: str) -> tuple[Array, Array, Array, tuple[str, ...]]:
    """t [s] (continuous over joined logs), u, y on the files' own time base, and the file names."""
    base = BY_KEY[key]
    paths = record_paths(Path(data_root), base)
    if not paths:
        raise FileNotFoundError(f"no files {base.first}..{base.last} in {Path(data_root) / base.folder}")
    ts, us, ys = [], [], []
    offset = 0.0
    for path in paths:
        with path.open() as handle:
            header = [h.strip() for h in handle.readline().split(",")]
        if header[:3] != ["t", "u", "y"]:
            raise ValueError(f"{path}: expected columns t,u,y first, found {header}")
        table = np.loadtxt(path, delimiter=",", skiprows=1, usecols=(0, 1, 2), ndmin=2)
        u = table[:, 1]
        jumps = np.abs(np.diff(u))
        if jumps.size > 2 and u[-1] == u[0] and jumps[-1] > 3.0 * jumps[:-1].max():
            table = table[:-1]  # the dSPACE captures wrap round: the last sample is the first again
        t = table[:, 0] - table[0, 0]
        ts.append(t + offset)
        offset = float(ts[-1][-1] + np.median(np.diff(t)))  # the next log starts one step later
        us.append(table[:, 1])
        ys.append(table[:, 2])
    return np.concatenate(ts), np.concatenate(us), np.concatenate(ys), tuple(p.name for p in paths)


def coarsen(kind: str, t: Array, x: Array) -> Array:
    """The native-time signal ``x`` on the record's final uniform grid (a linear operation):
    block means of :data:`PIEZO_BLOCK` samples for the piezo, linear interpolation onto the
    median step for the muscle."""
    if kind == "piezo":
        n = x.size // PIEZO_BLOCK * PIEZO_BLOCK
        return np.asarray(x[:n].reshape(-1, PIEZO_BLOCK).mean(axis=1), dtype=np.float64)
    step = float(np.median(np.diff(t)))
    grid = t[0] + step * np.arange(int(np.floor((t[-1] - t[0]) / step)) + 1)
    return np.asarray(np.interp(grid, t, x), dtype=np.float64)


def noise_estimate(y: Array, resolution: float) -> float:
    """Output noise [y units]: the 10th percentile over windows of the RMS second difference / sqrt(6)
    (white noise on the quietest stretches), floored at the quantisation noise resolution/sqrt(12)."""
    e2 = np.diff(y, 2)
    width = max(20, y.size // 50)
    n = e2.size // width
    rms = np.sqrt(np.mean(e2[: n * width].reshape(n, width) ** 2, axis=1))
    return max(float(np.percentile(rms, 10)) / np.sqrt(6.0), resolution / np.sqrt(12.0))


def resolution(y: Array) -> float:
    """The output's quantisation step: the 5th percentile of the non-zero sample-to-sample changes."""
    steps = np.abs(np.diff(y))
    steps = steps[steps > 1e-12]
    return float(np.percentile(steps, 5)) if steps.size else 0.0
