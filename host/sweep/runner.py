"""One attempt of one cell: its commands run as subprocesses in a folder of their own.

Standard library only, because it runs inside a Ray worker as well as in the local pool. A
subprocess per step isolates crashes (a segfault or an out-of-memory kill is a failed cell, not
a dead sweep) and makes a timeout killable: each step starts its own process group, which gets
SIGTERM at the deadline (so an edge run vents the valve and flushes its telemetry) and SIGKILL
5 s later. stdout and stderr go to files in the cell's folder, never into pipes that can fill.

The outcome is plain data: ``done`` with metrics (a step's ``--json`` result flattened to
``step.key`` columns) and the exit status, or ``error`` with its kind:

* ``timeout``: the cell ran past ``timeout_s``;
* ``signal``: a step died from a signal (killed, crashed, out of memory);
* ``error``: a step exited non-zero without a result;
* ``usage``: exit status 2, pmactl's "bad input"; never retried, it would fail the same way.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

KILL_GRACE_S = 5.0
ERROR_TAIL_LINES = 4

_running_lock = threading.Lock()
_running: set[int] = set()  # process-group ids of the steps running in this process
_cancelled: set[int] = set()  # groups stopped by cancel_running: their attempts are not results


def run_attempt(spec: dict[str, Any]) -> dict[str, Any]:
    """Run one attempt described by ``spec`` (see :func:`host.sweep.engine.attempt_spec`); never raises."""
    started, host = time.monotonic(), socket.gethostname()
    workdir, temporary = _workdir(spec)
    outcome: dict[str, Any] = {"key": spec["key"], "attempt": spec["attempt"], "host": host, "workdir": str(workdir)}
    metrics: dict[str, Any] = {}
    cpu_s, exit_code = 0.0, 0
    try:
        for name, text in spec["files"].items():
            (workdir / name).write_text(text)
        env = {**os.environ, **spec["env"], **_thread_env(spec["threads"]), "PYTHONUNBUFFERED": "1"}
        deadline = started + float(spec["timeout_s"])
        for step in spec["steps"]:
            argv = step["argv"] if step["program"] else [sys.executable, "-m", "host.cli", *step["argv"]]
            result = _run_step(argv, workdir, step["name"], env, deadline, bool(spec.get("die_with_parent")))
            cpu_s += result["cpu_s"]
            exit_code = result["exit_code"]
            if result["error_kind"]:
                outcome.update(outcome="error", error_kind=result["error_kind"], error=result["error"])
                break
            found = _read_json(step, workdir)
            if found is not None:
                metrics.update(flatten(found, step["name"]))
            if exit_code != 0:
                if found is None:
                    kind = "usage" if exit_code == 2 else "error"
                    outcome.update(outcome="error", error_kind=kind, error=_tail(workdir, step["name"], exit_code))
                else:  # a result with a failing status (an edge run that ended in a fault): the cell is done
                    outcome.update(outcome="done", error=_tail(workdir, step["name"], exit_code))
                break
        else:
            outcome["outcome"] = "done"
        outcome.setdefault("outcome", "done")
    except OSError as exc:
        outcome.update(outcome="error", error_kind="error", error=f"{exc.__class__.__name__}: {exc}")
    finally:
        if temporary:
            shutil.rmtree(workdir, ignore_errors=True)
    outcome.update(metrics=metrics, exit_code=exit_code, cpu_s=round(cpu_s, 3))
    outcome["elapsed_s"] = round(time.monotonic() - started, 3)
    outcome.setdefault("error_kind", None)
    outcome.setdefault("error", "")
    return outcome


def cancel_running(grace_s: float = KILL_GRACE_S) -> None:
    """Stop every step this process is running (the local sweep was interrupted): SIGTERM, then SIGKILL."""
    with _running_lock:
        groups = list(_running)
        _cancelled.update(groups)
    _signal_groups(groups, signal.SIGTERM)
    end = time.monotonic() + grace_s
    while time.monotonic() < end:
        with _running_lock:
            if not _running:
                return
        time.sleep(0.05)
    with _running_lock:
        _signal_groups(list(_running), signal.SIGKILL)


def flatten(value: Any, prefix: str) -> dict[str, Any]:
    """A JSON result as flat columns: ``{"a": {"b": 1}, "c": [x, y]}`` -> ``a.b``, ``c.0``, ``c.1``, ``c.n``."""
    if isinstance(value, dict):
        out: dict[str, Any] = {}
        for key, item in value.items():
            out.update(flatten(item, f"{prefix}.{key}"))
        return out
    if isinstance(value, list):
        if all(not isinstance(v, dict | list) for v in value):
            return {prefix: json.dumps(value), f"{prefix}.n": len(value)}
        out = {f"{prefix}.n": len(value)}
        for i, item in enumerate(value):
            out.update(flatten(item, f"{prefix}.{i}"))
        return out
    return {prefix: value}


def _run_step(
    argv: list[str], workdir: Path, name: str, env: dict[str, str], deadline: float, orphan_guard: bool
) -> dict:
    remaining = deadline - time.monotonic()
    if remaining <= 0:
        return {"cpu_s": 0.0, "exit_code": -1, "error_kind": "timeout", "error": f"timed out before step {name}"}
    finished, timed_out = threading.Event(), threading.Event()
    with open(workdir / f"{name}.stdout", "wb") as out, open(workdir / f"{name}.stderr", "wb") as err:
        try:
            proc = subprocess.Popen(
                argv, cwd=workdir, stdin=subprocess.DEVNULL, stdout=out, stderr=err, env=env,
                start_new_session=True, preexec_fn=_die_with_parent if orphan_guard else None,
            )  # fmt: skip
        except OSError as exc:
            return {"cpu_s": 0.0, "exit_code": -1, "error_kind": "error", "error": f"step {name}: {argv[0]}: {exc}"}
        with _running_lock:
            _running.add(proc.pid)
        watchdog = threading.Thread(
            target=_watch,
            args=(proc.pid, remaining, finished, timed_out),
            name=f"sweep-timeout-{proc.pid}",
            daemon=True,
        )
        watchdog.start()
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        finally:
            finished.set()
            watchdog.join()
            with _running_lock:
                _running.discard(proc.pid)
                cancelled = proc.pid in _cancelled
                _cancelled.discard(proc.pid)
    proc.returncode = code = os.waitstatus_to_exitcode(status)
    cpu_s = usage.ru_utime + usage.ru_stime
    if timed_out.is_set():
        _signal_groups([proc.pid], signal.SIGKILL)  # whatever the step left behind in its group
        return {"cpu_s": cpu_s, "exit_code": code, "error_kind": "timeout", "error": f"step {name}: timed out"}
    if cancelled:
        return {"cpu_s": cpu_s, "exit_code": code, "error_kind": "cancelled", "error": "sweep interrupted"}
    if code < 0:
        sig = signal.Signals(-code).name
        return {"cpu_s": cpu_s, "exit_code": code, "error_kind": "signal", "error": f"step {name}: killed by {sig}"}
    return {"cpu_s": cpu_s, "exit_code": code, "error_kind": None, "error": ""}


def _watch(pgid: int, timeout_s: float, finished: threading.Event, timed_out: threading.Event) -> None:
    """SIGTERM the step's group at its deadline, SIGKILL after the grace period."""
    if finished.wait(timeout_s):
        return
    timed_out.set()
    _signal_groups([pgid], signal.SIGTERM)
    if not finished.wait(KILL_GRACE_S):
        _signal_groups([pgid], signal.SIGKILL)


def _signal_groups(groups: list[int], sig: signal.Signals) -> None:
    for pgid in groups:
        try:
            os.killpg(pgid, sig)
        except (ProcessLookupError, PermissionError):
            pass


def _die_with_parent() -> None:  # pragma: no cover - runs in the forked child
    """Linux: SIGTERM this step when the worker that started it dies (a Ray worker killed mid-task)."""
    import ctypes

    ctypes.CDLL(None).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


def _read_json(step: dict[str, Any], workdir: Path) -> dict[str, Any] | None:
    source = step["json"]
    if source == "none":
        return None
    path = workdir / (source.removeprefix("file:") if source.startswith("file:") else f"{step['name']}.stdout")
    try:
        text = path.read_text()
    except OSError:
        return None
    try:
        found = json.loads(text)
    except json.JSONDecodeError:  # a line of text before the JSON: take the last JSON line
        lines = [line for line in text.splitlines() if line.startswith("{")]
        try:
            found = json.loads(lines[-1]) if lines else None
        except json.JSONDecodeError:
            found = None
    return found if isinstance(found, dict) else None


def _tail(workdir: Path, name: str, code: int) -> str:
    try:
        lines = (workdir / f"{name}.stderr").read_text(errors="replace").strip().splitlines()
    except OSError:
        lines = []
    text = " | ".join(line.strip() for line in lines[-ERROR_TAIL_LINES:])
    return f"step {name}: exit {code}" + (f": {text[-400:]}" if text else "")


def _workdir(spec: dict[str, Any]) -> tuple[Path, bool]:
    """A fresh folder for this attempt: under the sweep's output when the worker shares it, else a temporary one."""
    root = spec.get("workdir_root")
    if not root:
        return Path(tempfile.mkdtemp(prefix=f"pmactl-sweep-{spec['key']}-")), True
    parent = Path(root) / spec["key"]
    parent.mkdir(parents=True, exist_ok=True)
    n = int(spec["attempt"])
    while True:  # an attempt orphaned by a killed sweep may still be writing its folder: never reuse one
        try:
            path = parent / f"attempt-{n}"
            path.mkdir()
            return path, False
        except FileExistsError:
            n += 1


def _thread_env(threads: int) -> dict[str, str]:
    """BLAS/OpenMP/torch threads = the CPUs the cell reserved: same numbers in the local pool and on Ray."""
    value = str(max(1, int(threads)))
    return {name: value for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
