"""BLAS threads sized to the problem and to the machine's idle cores (threadpoolctl).

OpenBLAS starts one thread per core and its threads spin while they wait for work. On a
shared 2-core machine with another CPU-bound job, every small matrix product then waits for a
core that is busy elsewhere: fits were 5-67x slower with the default threads than with one
(issue 12's measurements, ``bench/hysteresis_bench.py`` reproduces them). The fits here are
tall and skinny (samples x tens to hundreds of parameters), so threads only pay for the
largest products, and only on cores nobody else is using.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

# floating-point work (samples x parameters^2) below which one thread is as fast as several:
# a 4096-row block times 211 Preisach nodes (~2e8) runs in ~10 ms on one core
PARALLEL_WORK = 5e9


def available_cpus() -> int:
    """Cores this process may run on (its affinity mask, not the machine's count)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def idle_cpus(cpus: int) -> int:
    """Cores not busy with other work: ``cpus`` minus the 1-minute load of everything but us."""
    try:
        load = os.getloadavg()[0]
    except OSError:
        return cpus
    others = max(0.0, load - 1.0)  # this process is (about to be) one unit of the load
    return max(1, min(cpus, round(cpus - others)))


def threads_for(work: float, cpus: int | None = None) -> int:
    """BLAS threads for ``work`` floating-point operations: 1 unless large, never more than idle cores."""
    cpus = available_cpus() if cpus is None else cpus
    if work < PARALLEL_WORK or cpus == 1:
        return 1
    return max(1, min(idle_cpus(cpus), int(work // PARALLEL_WORK) + 1))


@contextmanager
def blas_threads(work: float) -> Iterator[int]:
    """Limit BLAS (OpenBLAS, MKL, BLIS) to :func:`threads_for` ``(work)`` threads inside the block.

    Yields the count. ``PMACTL_BLAS_THREADS`` overrides the choice (``0``: leave BLAS alone,
    which is what the benchmark compares against).
    """
    override = os.environ.get("PMACTL_BLAS_THREADS")
    threads = threads_for(work) if override is None else int(override)
    if threads <= 0:
        yield 0
        return
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=threads, user_api="blas"):
        yield threads
