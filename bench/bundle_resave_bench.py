"""Readers during re-saves: how often does ``load_bundle`` fail while a bundle is rewritten?

One process loads the bundle in a loop while this one re-saves it for S seconds (the model
fitted once on the shipped example data). Prints a table: re-saves, loads, failed loads, CPU s.
Run it against another checkout with ``PYTHONPATH=/path/to/checkout python bench/bundle_resave_bench.py``.

    python bench/bundle_resave_bench.py [--seconds 5]
"""

from __future__ import annotations

import argparse
import multiprocessing
import tempfile
import time
from pathlib import Path

from edge.runtime.bundle import load_bundle
from host.data import load_measurement
from host.examples import example_path
from host.workflow import make_estimator, rest_state
from models_export.bundle import write_bundle


def reader(directory: str, ready, stop, result) -> None:  # noqa: ANN001 - multiprocessing primitives
    loads = failures = 0
    errors: dict[str, int] = {}
    start = time.process_time()
    while not stop.is_set():
        try:
            load_bundle(directory)
        except Exception as exc:  # noqa: BLE001 - every failure counts
            failures += 1
            key = f"{type(exc).__name__}: {str(exc)[-60:]}"
            errors[key] = errors.get(key, 0) + 1
        loads += 1
        ready.set()
    result.put((loads, failures, time.process_time() - start, errors))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=5.0, help="wall time spent re-saving")
    args = parser.parse_args()
    train = load_measurement(example_path("train"))
    estimator = make_estimator("dpi").fit(train.u, train.y)
    forward, inverse = rest_state(estimator.model_, float(train.u.min()))
    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp) / "bundle"
        write_bundle(directory, forward, inverse, units=("bar", "mm"))
        context = multiprocessing.get_context("spawn")
        ready, stop, result = context.Event(), context.Event(), context.Queue()
        process = context.Process(target=reader, args=(str(directory), ready, stop, result))
        process.start()
        ready.wait(60)
        start, saves = time.process_time(), 0
        deadline = time.monotonic() + args.seconds
        while time.monotonic() < deadline:
            write_bundle(directory, forward, inverse, units=("bar", "mm"))
            saves += 1
        writer_cpu = time.process_time() - start
        stop.set()
        loads, failures, reader_cpu, errors = result.get(timeout=60)
        process.join()
    import edge.runtime.bundle as module

    print(f"code: {Path(module.__file__).resolve().parents[2]}")
    print(f"{'re-saves':>9} {'loads':>7} {'failed':>7} {'writer CPU s':>13} {'reader CPU s':>13}")
    print(f"{saves:>9} {loads:>7} {failures:>7} {writer_cpu:>13.2f} {reader_cpu:>13.2f}")
    for message, count in sorted(errors.items(), key=lambda kv: -kv[1])[:3]:
        print(f"  {count:>5} x {message}")


if __name__ == "__main__":
    main()
