"""pmactl sweep on a real local Ray instance: the same rows as the local pool; a killed worker retried.

One Ray instance for the module (2 CPUs, a small object store; start-up is a few seconds),
shut down afterwards. Skipped cleanly where ray is not installed (an install without the
``cluster`` extra); CI installs the extra, so it runs there.
"""

from __future__ import annotations

import logging

import pytest

from host.sweep.backends import RayBackend
from host.sweep.engine import run_sweep
from host.sweep.matrix import load_matrix
from tests.test_sweep import comparable_rows, local_sweep, record_and_fit

ray = pytest.importorskip("ray", reason="ray not installed (pip install 'pmactl[cluster]')")


@pytest.fixture(scope="module")
def ray_instance():
    ray.init(num_cpus=2, object_store_memory=80 * 2**20, include_dashboard=False, logging_level=logging.WARNING)
    ray.get(ray.remote(lambda: None).remote())  # the driver's helper threads start here, not inside a test
    yield ray
    ray.shutdown()


def ray_sweep(matrix, out):  # noqa: ANN001, ANN201
    loaded = load_matrix(matrix)
    backend = RayBackend(None, None, loaded.resources)  # Ray is initialised: the backend uses it as it is
    try:
        return run_sweep(loaded, out, backend)
    finally:
        backend.close()


def test_ray_gives_the_same_rows_as_the_local_pool(tmp_path, ray_instance):
    matrix = record_and_fit(tmp_path / "m.sweep.toml", models='["pi", "preisach"]', seeds="1..2", limit=0.5)
    on_ray = ray_sweep(matrix, tmp_path / "ray")
    local = local_sweep(matrix, tmp_path / "local", 2)
    assert len(on_ray.rows) == len(local.rows) == 4
    assert "Ray" in on_ray.backend and "local pool" in local.backend
    assert {r["status"] for r in on_ray.rows} == {"pass", "fail"}  # pi misses 0.5 %, preisach meets it
    assert comparable_rows(matrix, tmp_path / "ray") == comparable_rows(matrix, tmp_path / "local")
    assert ray_instance.is_initialized()  # a sweep leaves a Ray it did not start running


def test_a_killed_ray_worker_is_retried(tmp_path, ray_instance):
    """The cell's first step kills the Ray worker running it (SIGKILL, once): Ray reports the dead
    worker, the sweep retries the cell per the matrix's policy, and the row passes on attempt 2."""
    marker = tmp_path / "killed-once"
    kill_worker = (
        '[[before]]\nname = "kill"\nprogram = true\njson = "none"\n'
        'args = ["{python}", "-c", "import os, pathlib, sys; m = pathlib.Path(sys.argv[1]); '
        f'm.exists() or (m.touch(), os.kill(os.getppid(), 9))", "{marker}"]\n'
    )
    matrix = record_and_fit(tmp_path / "m.sweep.toml", seeds="1..1", extra_steps=kill_worker)
    result = ray_sweep(matrix, tmp_path / "out")
    assert marker.exists()
    (row,) = result.rows
    assert row["status"] == "pass" and row["attempts"] == 2
    journal = (tmp_path / "out" / "cells.jsonl").read_text().splitlines()
    assert len(journal) == 2 and '"error_kind": "signal"' in journal[0] and "Ray" in journal[0]
