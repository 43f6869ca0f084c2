"""Where cells run: an embedded local pool (default) or tasks on a Ray cluster (``--ray``).

Both run :func:`host.sweep.runner.run_attempt` on the same plain-data spec, so a cell gives the
same row either way. The sweep, not the backend, retries: Ray tasks are submitted with
``max_retries=0`` and a worker that dies comes back as a failed attempt of kind ``signal``, so
one policy (the matrix's ``retries`` / ``retry_on``) is counted in one place, locally and on Ray.

Ray is imported only here and only for ``--ray`` (the ``cluster`` extra); nothing in ``edge``
imports it.
"""

from __future__ import annotations

import logging
import os
import socket
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor
from concurrent.futures import wait as wait_futures
from typing import Any, Protocol

from edge.errors import ConfigError
from host.sweep import runner
from host.sweep.presets import Resources

Outcome = dict[str, Any]
PROBE_TIMEOUT_S = 5.0


class Backend(Protocol):
    description: str
    capacity: int  # cells in flight at once
    shares_filesystem: bool  # workers can write into the sweep's output folder
    orphan_guard: bool  # steps die with their worker process (Ray workers can be killed under them)

    def submit(self, spec: dict[str, Any]) -> object: ...

    def wait(self, handles: list[object], timeout_s: float) -> list[tuple[object, Outcome]]: ...

    def cancel(self) -> None: ...

    def close(self) -> None: ...


class LocalBackend:
    """A thread pool on this machine; each thread runs one cell's subprocesses at a time."""

    shares_filesystem = True
    orphan_guard = False

    def __init__(self, workers: int | None, resources: Resources) -> None:
        cpus = workers or os.cpu_count() or 1
        slots = max(1, int(cpus // max(1.0, resources.num_cpus)))
        available_mb = _available_memory_mb()
        if available_mb is not None:
            slots = min(slots, max(1, available_mb // resources.memory_mb))
        for amount in resources.custom.values():  # this machine is taken to have one of each (one rig)
            slots = min(slots, max(1, int(1.0 // amount)))
        self.capacity = slots
        self.description = f"local pool, {slots} worker{'s' if slots > 1 else ''}"
        self._pool = ThreadPoolExecutor(max_workers=slots, thread_name_prefix="pmactl-sweep")

    def submit(self, spec: dict[str, Any]) -> object:
        return self._pool.submit(runner.run_attempt, spec)

    def wait(self, handles: list[object], timeout_s: float) -> list[tuple[object, Outcome]]:
        futures: list[Future[Outcome]] = handles  # type: ignore[assignment]
        done, _ = wait_futures(futures, timeout=timeout_s, return_when=FIRST_COMPLETED)
        return [(f, f.result()) for f in done]

    def cancel(self) -> None:
        runner.cancel_running()

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


class RayBackend:
    """Ray tasks on a cluster: ``address`` as ``ray.init`` takes it, or an already initialised Ray."""

    orphan_guard = True

    def __init__(self, address: str | None, workers: int | None, resources: Resources) -> None:
        try:
            import ray
        except ModuleNotFoundError:
            raise ConfigError(
                "--ray needs the cluster extra (ray is not installed); install it with: pip install 'pmactl[cluster]'"
            ) from None
        self._ray = ray
        self._started = False
        if not ray.is_initialized():
            options: dict[str, Any] = {"include_dashboard": False, "logging_level": logging.WARNING}
            if address == "local":
                options.update(num_cpus=workers or os.cpu_count(), object_store_memory=80 * 2**20)
            _probe(address)
            try:
                ray.init(address=address, **options)
            except (ConnectionError, ValueError, RuntimeError) as exc:
                first = str(exc).strip().splitlines()[0] if str(exc).strip() else exc.__class__.__name__
                raise ConfigError(
                    f"--ray {address}: cannot connect ({first}); start a cluster with `ray start --head` "
                    "or use --ray local for a Ray instance on this machine"
                ) from None
            self._started = True
        totals = ray.cluster_resources()
        for name, amount in resources.custom.items():
            if totals.get(name, 0.0) < amount:
                raise ConfigError(
                    f"--ray: the cluster has no resource {name!r} (cells need {amount:g}); start the nodes "
                    f"that have it with ray start --resources '{{\"{name}\": 1}}'"
                )
        slots = int(totals.get("CPU", 1.0) // resources.num_cpus)
        for name, amount in resources.custom.items():
            slots = min(slots, int(totals[name] // amount))
        if slots < 1:
            raise ConfigError(
                f"--ray: no node has the {resources.num_cpus:g} CPUs a cell needs ({totals.get('CPU', 0):g} in all)"
            )
        self.capacity = min(slots, workers) if workers else slots
        self.shares_filesystem = self._single_host(address)
        self._remote = ray.remote(runner.run_attempt).options(
            num_cpus=resources.num_cpus,
            memory=resources.memory_mb * 2**20,
            resources=resources.custom or None,
            max_retries=0,
        )
        self._inflight: set[Any] = set()
        where = "local Ray instance" if self._started and address == "local" else f"Ray cluster {address or '(found)'}"
        self.description = f"{where}, {self.capacity} cells at once ({totals.get('CPU', 0):g} CPUs)"

    def submit(self, spec: dict[str, Any]) -> object:
        ref = self._remote.remote(spec)
        self._inflight.add(ref)
        return ref

    def wait(self, handles: list[object], timeout_s: float) -> list[tuple[object, Outcome]]:
        ray = self._ray
        ready, rest = ray.wait(handles, num_returns=1, timeout=timeout_s)
        if ready and rest:
            more, _ = ray.wait(rest, num_returns=len(rest), timeout=0)
            ready += more
        results = []
        for ref in ready:
            self._inflight.discard(ref)
            try:
                results.append((ref, ray.get(ref)))
            except ray.exceptions.RayError as exc:  # the worker or its node died under the task
                text = str(exc).strip().splitlines()
                results.append(
                    (ref, {"outcome": "error", "error_kind": "signal", "error": f"Ray: {text[0] if text else exc}"})
                )
        return results

    def cancel(self) -> None:
        for ref in list(self._inflight):
            try:
                self._ray.cancel(ref, force=True)
            except Exception:  # noqa: BLE001 - best effort while stopping; the task may have just finished
                pass

    def close(self) -> None:
        if self._started:
            self._ray.shutdown()

    def _single_host(self, address: str | None) -> bool:
        """True when every node is this machine (then cells write into --out, as in the local pool)."""
        if address and address.startswith("ray://"):
            return False
        here = self._ray.util.get_node_ip_address()
        return all(node["NodeManagerAddress"] == here for node in self._ray.nodes() if node.get("Alive"))


def make_backend(ray_address: str | None, workers: int | None, resources: Resources) -> Backend:
    """``--ray`` absent: the local pool. ``--ray local``: a fresh Ray on this machine; else ``ray.init(address)``."""
    if workers is not None and workers < 1:
        raise ConfigError(f"--workers {workers}: give at least 1")
    if ray_address is None:
        return LocalBackend(workers, resources)
    return RayBackend(ray_address, workers, resources)


def _probe(address: str | None) -> None:
    """Refuse an address nothing answers at: ray.init retries an unreachable head for minutes."""
    if address in (None, "auto", "local"):
        return
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        raise ConfigError(f"--ray {address}: give HOST:PORT, ray://HOST:PORT, auto or local")
    try:
        socket.create_connection((host, int(port)), timeout=PROBE_TIMEOUT_S).close()
    except OSError as exc:
        raise ConfigError(
            f"--ray {address}: nothing answers there ({exc.strerror or exc}); check the head node's address "
            "(ray status on the head prints it) or use --ray local"
        ) from None


def _available_memory_mb() -> int | None:
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) // 1024
    except OSError:
        pass
    return None
