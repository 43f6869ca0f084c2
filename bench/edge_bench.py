"""Benchmark of the edge loop: per-tick compute inside the running loop, real-time lateness.

Usage: python bench/edge_bench.py [--seconds 60] [--skip-realtime] [--before DIR] [--repeats 3]
       python bench/edge_bench.py --only-rig-commands 3 [--rig-seconds 20]
       python bench/edge_bench.py --only-live 3 [--rig-seconds 20]
       python bench/edge_bench.py --only-lean 3 [--compute-seconds 10] [--before DIR]

1. Per-tick breakdown (median / p99 us) of a 20 s lockstep run on the HIL at 1 kHz with a
   Preisach lookup-table inverse and a 2-5-10-1 ONNX correction (Ai2019's BP net shape):
   read, inverse, NN, PID, limits + safety, write, log. read and write run the emulated chips
   and integrate the plant inside the bus transfers, so they overstate a real bus's CPU cost.
   Then the whole-tick compute (supervisor + control law + telemetry row) of untimed runs, with
   and without the ONNX net: wall time per tick, thread CPU time per tick (a separate run: the
   CPU clock calls cost time themselves), and the same runs of the pre-v2 runtime when its
   source is given (``--before DIR``, e.g. ``git archive 4df3193 | tar -x -C DIR``) so the
   ratio comes from one process on one loaded machine.
1a. ``--only-lean N``: the whole tick (table only, and with the twin) against a flat loop doing
   the same arithmetic (issue 32's reference), interleaved, wall beside CPU, ratios of medians.
1b. ``--only-twin N``: the whole-tick compute with the forward twin on (the default), off (the
   table-only tick) and with ``[adapt]``, N repeats, wall beside CPU, ratios to table-only.
2. Lateness of a real-time 1 kHz run (``--seconds``) over the serial DAQ protocol on a pty, the
   HIL in its own process (``pmactl hil serve``): median, p99, p99.9, max, overruns per 1e4
   ticks, with and without SCHED_FIFO.
2b. ``edge run``, ``edge record`` and ``edge probe`` in real time at 1 kHz on the emulated
   ADS1015 rig (in-process, ``sim://rig?clock=realtime``), interleaved: overruns, lateness, the
   process's CPU time per wall second.
2c. Whole-tick wall time (read to log) of 1 kHz runs with and without ``--live`` (a real
   WebSocket client subscribed to every channel in its own process), on the lockstep clock (the
   loop flat out: the publisher gets more ticks per wall second than in real time) and the
   real-time clock.
3. The same schedule in C (bench/c_sleep_loop.c, compiled with cc) for 1e4 ticks, with and
   without SCHED_FIFO: what this machine allows any program.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from edge.control.reference import parse_reference
from edge.runtime.bundle import load_bundle
from edge.runtime.run import PHASES, EdgeRuntime
from models_export.bundle import add_correction

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
from tests.edge_helpers import fit_bundle, rig_config  # noqa: E402  (the tests' rig and bundle)
from tests.onnx_models import mlp  # noqa: E402  (the test helper builds the ONNX net)


class Timed:
    """Wraps an object's ``step`` and records its duration [ns] per call."""

    def __init__(self, inner: object, n: int) -> None:
        self._inner, self.ns, self.count = inner, np.zeros(n, dtype=np.int64), 0

    def step(self, *args: object, **kwargs: object) -> float:
        start = time.perf_counter_ns()
        value = self._inner.step(*args, **kwargs)  # type: ignore[attr-defined]
        if self.count < len(self.ns):
            self.ns[self.count] = time.perf_counter_ns() - start
        self.count += 1
        return value

    def __getattr__(self, name: str) -> object:
        return getattr(self._inner, name)


def make_bundle(root: Path) -> Path:
    """The Preisach bundle of the tests, with a small 2-5-10-1 net as its correction."""
    bundle = fit_bundle(root / "bundle")
    path, _ = mlp(root / "bp.onnx", scale=0.05)
    add_correction(
        bundle, path, {"features": ["reference_mm", "feedforward_bar"], "input": "features", "output": "correction_bar"}
    )
    return bundle


def profiled_run(
    bundle: Path,
    seconds: float,
    timed: bool,
    profile: bool | str = True,
    nn: bool = True,
    twin: bool = True,
    adapt: bool = False,
    feedforward: dict | None = None,
):
    """A lockstep run with per-phase timing; ``timed`` also wraps inverse, NN and PID;
    ``feedforward``: the rig config's [feedforward] section (role, twin)."""
    n = int(seconds * 1000)
    with tempfile.TemporaryDirectory() as tmp:
        edge = EdgeRuntime(
            rig_config(adapt={"enabled": adapt}, feedforward=feedforward or {}),
            load_bundle(bundle),
            parse_reference("sine:amplitude=30,frequency=0.2,offset=40"),
            telemetry_path=Path(tmp) / "t.pmt",
            profile=profile,
            use_correction=nn,
            twin=twin,
        )
        if timed:
            controller = edge.controller
            controller.inverse = Timed(controller.inverse, n)
            controller.correction = Timed(controller.correction, n)
            controller.pid = Timed(controller.pid, n)
        wall, cpu = time.perf_counter(), time.process_time()
        summary = edge.run(seconds).as_dict()
        summary["run_wall_s"], summary["run_cpu_s"] = time.perf_counter() - wall, time.process_time() - cpu
    return edge, summary


def breakdown(bundle: Path, seconds: float = 20.0) -> None:
    edge, summary = profiled_run(bundle, seconds, timed=True)
    controller = edge.controller
    phases = edge.phase_ns[: summary["ticks"]] / 1e3
    inverse, nn, pid = controller.inverse.ns / 1e3, controller.correction.ns / 1e3, controller.pid.ns / 1e3
    parts = {
        "read (emulated chips + plant)": phases[:, PHASES.index("read")],
        "inverse (lookup table)": inverse,
        "NN (onnxruntime, 2-5-10-1)": nn,
        "PID": pid,
        "limits + safety (+ timer cost)": phases[:, PHASES.index("control")] - inverse - nn - pid,
        "write (emulated chips + plant)": phases[:, PHASES.index("write")],
        "log (telemetry row + error sums)": phases[:, PHASES.index("log")],
    }
    print(f"\nPer-tick breakdown, lockstep HIL, 1 kHz, {summary['ticks']} ticks (us, wall)")
    print(f"{'phase':<34} {'median':>8} {'p99':>8}")
    for name, values in parts.items():
        print(f"{name:<34} {np.median(values):8.2f} {np.percentile(values, 99):8.2f}")


def whole_tick(
    bundle: Path, seconds: float, nn: bool, repeats: int, **variant: object
) -> list[tuple[float, float, float, float, float]]:
    """(wall median, wall p99, CPU median, CPU p99 [us], run CPU / wall) of each repeat."""
    rows = []
    for _ in range(repeats):
        edge, summary = profiled_run(bundle, seconds, timed=False, profile=True, nn=nn, **variant)
        phases = edge.phase_ns[: summary["ticks"]] / 1e3
        wall = phases[:, PHASES.index("control")] + phases[:, PHASES.index("log")]
        edge, cpu_summary = profiled_run(bundle, seconds, timed=False, profile="cpu", nn=nn, **variant)
        cpu = edge.phase_ns[: cpu_summary["ticks"], PHASES.index("cpu")] / 1e3
        share = summary["run_cpu_s"] / summary["run_wall_s"]
        rows.append((np.median(wall), np.percentile(wall, 99), np.median(cpu), np.percentile(cpu, 99), share))
    return rows


BEFORE_SCRIPT = """
import sys, tempfile, time, json
from pathlib import Path
import numpy as np
sys.path.insert(0, sys.argv[1])
from edge.control.reference import parse_reference
from edge.runtime.bundle import load_bundle
from edge.runtime.run import PHASES, EdgeRuntime
from tests.edge_helpers import rig_config
out = []
for _ in range(int(sys.argv[4])):
    with tempfile.TemporaryDirectory() as tmp:
        reference = parse_reference("sine:amplitude=30,frequency=0.2,offset=40")
        edge = EdgeRuntime(rig_config(), load_bundle(sys.argv[2]), reference,
                           telemetry_path=Path(tmp) / "t.pmt", profile=True, use_correction=sys.argv[5] == "1")
        wall, cpu = time.perf_counter(), time.process_time()
        s = edge.run(float(sys.argv[3])).as_dict()
        share = (time.process_time() - cpu) / (time.perf_counter() - wall)
    ph = edge.phase_ns[: s["ticks"]] / 1e3
    c = ph[:, PHASES.index("control")] + ph[:, PHASES.index("log")]
    out.append([float(np.median(c)), float(np.percentile(c, 99)), share])
print(json.dumps(out))
"""


def before(root: Path, bundle: Path, seconds: float, nn: bool, repeats: int) -> list[list[float]]:
    """The pre-v2 runtime's whole-tick compute, from its own source tree, in a subprocess."""
    import json
    import os

    env = {**os.environ, "PYTHONPATH": str(root)}
    result = subprocess.run(
        [sys.executable, "-c", BEFORE_SCRIPT, str(root), str(bundle), str(seconds), str(repeats), "1" if nn else "0"],
        capture_output=True, text=True, env=env, cwd=str(root), check=True,
    )  # fmt: skip
    return json.loads(result.stdout.strip().splitlines()[-1])


def compute_table(bundle: Path, seconds: float, repeats: int, before_root: Path | None) -> None:
    print(f"\nWhole-tick compute (supervisor + control law + telemetry row), {seconds:g} s lockstep runs x {repeats}")
    print("(us per tick; targets: median <= 8, p99 <= 20; run CPU/wall: share of the run the process had the CPU)")
    print(f"{'runtime':<28} {'wall med':>8} {'wall p99':>8} {'CPU med':>8} {'CPU p99':>8} {'CPU/wall':>8}")
    for nn in (False, True):
        label = "v2" + (" + ONNX net" if nn else "")
        for row in whole_tick(bundle, seconds, nn, repeats):
            print(f"{label:<28} {row[0]:8.2f} {row[1]:8.2f} {row[2]:8.2f} {row[3]:8.2f} {row[4]:8.2f}")
        if before_root is not None:
            old = "before v2" + (" + ONNX net" if nn else "")
            for med, p99, share in before(before_root, bundle, seconds, nn, repeats):
                print(f"{old:<28} {med:8.2f} {p99:8.2f} {'':>8} {'':>8} {share:8.2f}")


def realtime_run(bundle: Path, seconds: float, fifo: bool) -> dict:
    server = subprocess.Popen([sys.executable, "-m", "host.cli", "hil", "serve"], stdout=subprocess.PIPE, text=True)
    try:
        pty = server.stdout.readline().split()[1]
        config = rig_config("hil-serial.toml", rig={"io": f"serial://{pty}"}, loop={"realtime": fifo})
        edge = EdgeRuntime(config, load_bundle(bundle), parse_reference("sine:amplitude=30,frequency=0.2,offset=40"))
        summary = edge.run(seconds).as_dict()
    finally:
        server.send_signal(signal.SIGTERM)
        server.communicate(timeout=10)
    return summary


def rig_command(
    kind: str, bundle: Path, seconds: float, root: Path, clock: str = "realtime"
) -> tuple[dict, float, float]:
    """One 1 kHz ``edge run`` / ``record`` / ``probe`` on the emulated ADS1015 rig (sim://rig on
    ``clock``, the loop in this process): its lateness summary, wall s, CPU s."""
    from edge.runtime import record as recording
    from edge.runtime.probe import Probe

    # overrun_streak 1000: every command runs its full length on a loaded machine, so the
    # overrun counts compare (the default 5 in a row ends a run at the first stall)
    config = rig_config(buses={"i2c": {"url": f"sim://rig?clock={clock}"}}, safety={"overrun_streak": 1000})
    wall, cpu = time.perf_counter(), time.process_time()
    if kind == "edge run":
        reference = parse_reference("sine:amplitude=30,frequency=0.2,offset=40")
        lateness = EdgeRuntime(config, load_bundle(bundle), reference).run(seconds).lateness
    elif kind == "edge record":
        out = root / f"record-{time.monotonic_ns()}.csv"
        runtime, recorder = recording.record(config, "triangles", out, duration_s=seconds)
        lateness = recording.finish(runtime, recorder).summary.lateness
    else:
        probe = Probe(config)
        try:
            probe.run(seconds, lambda _: True, pace=False)
        finally:
            probe.close()
        lateness = probe.scheduler.stats.summary()
    return lateness, time.perf_counter() - wall, time.process_time() - cpu


def rig_commands_cpu(bundle: Path, seconds: float, repeats: int) -> None:
    """CPU per tick of the three commands in lockstep (the emulated chips and plant included):
    what a loaded machine's lateness cannot blur."""
    print(f"\nCPU per tick, lockstep emulated ADS1015 rig at 1 kHz, {seconds:g} s x {repeats} (us; ratio to edge run)")
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeats):
            row = {}
            for kind in ("edge run", "edge record", "edge probe"):
                lat, _, cpu = rig_command(kind, bundle, seconds, Path(tmp), "lockstep")
                row[kind] = cpu / max(lat["ticks"], 1) * 1e6
            base = row["edge run"]
            print("  ".join(f"{k} {v:6.1f} ({v / base:4.2f})" for k, v in row.items()))


def rig_commands_table(bundle: Path, seconds: float, repeats: int) -> None:
    print(f"\nReal-time 1 kHz on the emulated ADS1015 rig (sim://rig?clock=realtime), {seconds:g} s x {repeats}")
    print(f"{'command':<14} {'ticks':>7} {'overruns':>9} {'per 1e4':>8} {'p99 us':>7} {'max us':>8} {'CPU/wall':>8}")
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeats):
            for kind in ("edge run", "edge record", "edge probe"):
                lat, wall, cpu = rig_command(kind, bundle, seconds, Path(tmp))
                print(
                    f"{kind:<14} {lat['ticks']:7.0f} {lat['overruns']:9.0f} {lat['overruns_per_10k']:8.2f} "
                    f"{lat['lateness_p99_us']:7.0f} {lat['lateness_max_us']:8.0f} {cpu / wall:8.2f}"
                )


LIVE_CLIENT = """
import asyncio, json, sys, time
import websockets
async def main(port):
    for _ in range(400):
        try:
            ws = await websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"])
            break
        except OSError:
            await asyncio.sleep(0.05)
    n, first, last, sub = 0, None, None, 0
    async with ws:
        while True:
            try:
                m = await ws.recv()
            except websockets.ConnectionClosed:
                break
            if isinstance(m, str):
                op = json.loads(m)
                if op["op"] == "advertise":
                    for c in op["channels"]:
                        sub += 1
                        request = {"id": sub, "channelId": c["id"]}
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [request]}))
            else:
                n += 1
                last = time.monotonic()
                first = first or last
    print(n, (last - first) if first else 0.0)
asyncio.run(main(int(sys.argv[1])))
"""


def live_run(bundle: Path, seconds: float, live: bool, clock: str) -> tuple[np.ndarray, str]:
    """Whole-tick wall time [us] (every phase, read to log) of one 1 kHz run on the emulated rig,
    with a live view and a subscribed WebSocket client or without."""
    import socket

    from edge.runtime.live import LiveView

    config = rig_config(buses={"i2c": {"url": f"sim://rig?clock={clock}"}}, safety={"overrun_streak": 1000})
    edge = EdgeRuntime(
        config, load_bundle(bundle), parse_reference("sine:amplitude=30,frequency=0.2,offset=40"), profile=True
    )
    client, note = None, ""
    if live:
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        edge.live = LiveView(f"127.0.0.1:{port}", edge.layout.dtype, config.loop.rate_hz)
        client = subprocess.Popen([sys.executable, "-c", LIVE_CLIENT, str(port)], stdout=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 20
        while not edge.live.tick_channel.has_sinks() and time.monotonic() < deadline:
            time.sleep(0.05)
    summary = edge.run(seconds).as_dict()
    if client is not None:
        count, span = client.communicate(timeout=30)[0].split()
        note = f"client got {int(count)} messages, {int(count) / max(float(span), 1e-9):.0f}/s"
    phases = edge.phase_ns[: summary["ticks"], :4].sum(axis=1) / 1e3
    return phases, note


def live_table(bundle: Path, seconds: float, repeats: int) -> None:
    print(f"\nWhole tick (read to log, wall us) with and without --live, 1 kHz, {seconds:g} s runs x {repeats}")
    print(f"{'clock':<9} {'run':<22} {'median':>7} {'p99':>7} {'p99 ratio':>9}")
    for clock in ("lockstep", "realtime"):
        for _ in range(repeats):
            base, _ = live_run(bundle, seconds, False, clock)
            with_live, note = live_run(bundle, seconds, True, clock)
            p99 = np.percentile(base, 99), np.percentile(with_live, 99)
            print(f"{clock:<9} {'without':<22} {np.median(base):7.1f} {p99[0]:7.1f}")
            row = f"{np.median(with_live):7.1f} {p99[1]:7.1f} {p99[1] / p99[0]:9.2f}"
            print(f"{clock:<9} {'--live, client':<22} {row}  {note}")


def c_loop(fifo: bool, ticks: int = 10_000) -> tuple[int, int] | None:
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        return None
    binary = Path(tempfile.gettempdir()) / "pmactl_c_sleep_loop"
    subprocess.run([cc, "-O2", "-o", str(binary), str(HERE / "c_sleep_loop.c")], check=True)
    out = subprocess.run([str(binary), str(ticks)] + (["fifo"] if fifo else []), capture_output=True, text=True)
    if out.returncode:
        return None
    overruns, worst = out.stdout.split()
    return int(overruns), int(worst)


TWIN_VARIANTS = {"table only (no twin)": {"twin": False}, "+ twin": {}, "+ twin + [adapt]": {"adapt": True}}


def variant_table(bundle: Path, seconds: float, repeats: int, title: str, variants: dict[str, dict]) -> None:
    """Whole-tick compute of each variant (rows interleaved, so a busy spell of the machine hits
    every variant), with each CPU median as a ratio of the first variant's."""
    print(f"\n{title}, {seconds:g} s lockstep runs x {repeats} (us per tick)")
    print(f"{'tick':<28} {'wall med':>8} {'wall p99':>8} {'CPU med':>8} {'CPU p99':>8} {'CPU/wall':>8}")
    rows: dict[str, list] = {name: [] for name in variants}
    for _ in range(repeats):
        for name, variant in variants.items():
            rows[name] += whole_tick(bundle, seconds, False, 1, **variant)
    first = next(iter(variants))
    base = np.median([r[2] for r in rows[first]])
    for name, values in rows.items():
        for row in values:
            print(f"{name:<28} {row[0]:8.2f} {row[1]:8.2f} {row[2]:8.2f} {row[3]:8.2f} {row[4]:8.2f}")
        print(f"{'':<28} CPU median / {first}: {np.median([r[2] for r in values]) / base:.2f}x")


def twin_table(bundle: Path, seconds: float, repeats: int) -> None:
    """Whole-tick compute with the forward twin off, on, and with adaptation."""
    variant_table(bundle, seconds, repeats, "Whole-tick compute with the forward twin", TWIN_VARIANTS)


NET_VARIANTS: dict[str, dict[str, object]] = {
    "table, no twin": {"twin": False, "feedforward": {"role": "table"}},
    "table + table twin": {"twin": True, "feedforward": {"role": "table"}},
    "LSTM net + table twin": {"twin": True, "feedforward": {"role": "net"}},
    "LSTM net + net twin": {"twin": True, "feedforward": {"role": "net", "twin": "net"}},
}


def net_bundle(root: Path) -> Path:
    """An LSTM-NARMAX bundle whose nets step every tick: a 12 s ``edge record`` at 1 kHz on the
    emulated rig, trained for 3 epochs (its accuracy does not matter for the timing)."""
    from host.cli import main as pmactl

    recording, store = root / "rec.csv", root / "net-store"
    config = Path(__file__).resolve().parent.parent / "docs" / "examples" / "hil-rig.toml"
    for argv in (
        ["edge", "record", "--config", str(config), "--protocol", "sines", "--duration", "12", "--sample-hz", "1000",
         "--range", "0:6", "--out", str(recording)],
        ["train", "--model", "lstm-narmax", "--train", str(recording), "--units", "bar,mm", "--epochs", "3",
         "--save", str(store), "--json"],
    ):  # fmt: skip
        with contextlib.redirect_stdout(io.StringIO()):
            if pmactl(argv) != 0:
                raise SystemExit(f"pmactl {' '.join(argv)} failed")
    return store / "current"


def nets_table(root: Path, seconds: float, repeats: int) -> None:
    """Whole-tick compute with the LSTM-NARMAX inverse net stepping every tick, with the table
    twin and with the net twin, beside the table-only tick."""
    title = "Whole tick with the nets stepping every tick"
    variant_table(net_bundle(root), seconds, repeats, title, NET_VARIANTS)


def flat_tick(bundle: Path, seconds: float, between: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The reference for the whole tick: one flat loop doing the same arithmetic with no
    plumbing (issue 32): ADC scaling of two codes, the reference, the bundle's inverse table
    step, PID (filtered derivative, anti-windup), slew, clamp, and a telemetry row copied into a
    ring. Per-tick (wall, thread CPU) [us], each from its own pass (the CPU clock costs time).
    ``between``: the emulated rig's read and write (the HIL plant, ~60 us of other Python) run
    between the timed ticks, untimed, as they do around the runtime's tick."""
    import ctypes
    import math

    from edge.control.pid import PIDGains
    from edge.runtime.frame import frame_layout

    config = rig_config()
    c = config.control
    gains = PIDGains(c.kp_bar_per_mm, c.ki_bar_per_mm_s, c.kd_bar_s_per_mm, c.derivative_filter_s, 0.0, 6.0)
    reference = parse_reference("sine:amplitude=30,frequency=0.2,offset=40")
    n, dt = int(seconds * 1000), 1e-3
    rng = np.random.default_rng(0)
    codes = (rng.integers(0, 4096, size=(n, 2))).tolist()
    row_type = ctypes.c_double * 8
    row_bytes = ctypes.sizeof(row_type)
    layout = frame_layout(config.rig)  # the ring is as wide as the real frame's row
    ring = bytearray(1024 * layout.dtype.itemsize)
    out = []
    rig = EdgeRuntime(config, None, reference) if between else None
    for clock in (time.perf_counter_ns, time.thread_time_ns):
        inverse = load_bundle(bundle).inverse
        inverse.reset()
        row = row_type()
        source = memoryview(row).cast("B")
        integral, y_filtered, last, alpha = 0.0, 40.0, 0.0, dt / (gains.tau_d_s + dt)
        kp, ki, kd, slew = gains.kp, gains.ki, gains.kd, c.slew_bar_per_s * dt
        ns = np.zeros(n, dtype=np.int64)
        width = layout.dtype.itemsize
        for k in range(n):
            if rig is not None:
                rig.rig.read(rig.frame)
                rig.rig.write(rig.frame)
            start = clock()
            t = k * dt
            code_y, code_p = codes[k]
            y = code_y * 0.0366 - 2.0
            p = code_p * 0.00195 + 0.0
            r = reference(t)
            ff = inverse.step(r)
            if math.isfinite(ff):
                error = r - y
                previous = y_filtered
                y_filtered = previous + alpha * (y - previous)
                derivative = (y_filtered - previous) / dt
                increment = ki * error * dt
                total = kp * error + integral + increment - kd * derivative + ff
                if not ((total > 6.0 and error > 0) or (total < 0.0 and error < 0)):
                    integral += increment
                total = min(max(kp * error + integral - kd * derivative + ff, 0.0), 6.0)
                u = min(max(total, last - slew), last + slew)
                last = u = min(max(u, 0.0), 6.0)
            else:
                total, u = ff, 0.0
            row[0], row[1], row[2], row[3], row[4], row[5], row[6], row[7] = t, r, ff, total - ff, u, y, p, 1.0
            at = (k % 1024) * width
            ring[at : at + row_bytes] = source
            ns[k] = clock() - start
        out.append(ns / 1e3)
    if rig is not None:
        rig.rig.close()
    return out[0], out[1]


LEAN_BEFORE_SCRIPT = """
import sys, tempfile, json
from pathlib import Path
import numpy as np
sys.path.insert(0, sys.argv[1])
from edge.control.reference import parse_reference
from edge.runtime.bundle import load_bundle
from edge.runtime.run import PHASES, EdgeRuntime
from tests.edge_helpers import rig_config
out = []
for profile in (True, "cpu"):
    reference = parse_reference("sine:amplitude=30,frequency=0.2,offset=40")
    edge = EdgeRuntime(rig_config(), load_bundle(sys.argv[2]), reference, profile=profile, use_correction=False,
                       twin=sys.argv[4] == "1")
    s = edge.run(float(sys.argv[3])).as_dict()
    ph = edge.phase_ns[: s["ticks"]] / 1e3
    c = ph[:, PHASES.index("control")] + ph[:, PHASES.index("log")] if profile is True else ph[:, PHASES.index("cpu")]
    out += [float(np.median(c)), float(np.percentile(c, 99))]
print(json.dumps(out))
"""


def lean_before(root: Path, bundle: Path, seconds: float, twin: bool) -> tuple[float, float, float, float]:
    """The whole tick of another source tree (``--before DIR``), in a subprocess of this run."""
    import json
    import os

    env = {**os.environ, "PYTHONPATH": str(root)}
    result = subprocess.run(
        [sys.executable, "-c", LEAN_BEFORE_SCRIPT, str(root), str(bundle), str(seconds), "1" if twin else "0"],
        capture_output=True, text=True, env=env, cwd=str(root), check=True,
    )  # fmt: skip
    wall_med, wall_p99, cpu_med, cpu_p99 = json.loads(result.stdout.strip().splitlines()[-1])
    return wall_med, wall_p99, cpu_med, cpu_p99


def lean_table(bundle: Path, seconds: float, repeats: int, before_root: Path | None = None) -> None:
    """Issue 32: the whole tick (table feedforward, no net, no twin; with the twin) against the
    flat reference, interleaved in one process, wall beside CPU; ratios of medians. With
    ``before_root`` the same rows of that source tree (a subprocess), interleaved too."""
    print(f"\nWhole tick against a flat loop doing the same arithmetic, {seconds:g} s lockstep runs x {repeats}")
    print("(us per tick; whole tick = supervisor + control law + telemetry row; ratio = median / flat median)")
    print(f"{'tick':<39} {'wall med':>8} {'wall p99':>8} {'CPU med':>8} {'CPU p99':>8} {'wall x':>7} {'CPU x':>7}")
    flat_names = ("flat loop (reference)", "flat loop, HIL between")
    rows: dict[str, list[tuple[float, float, float, float]]] = {name: [] for name in flat_names}
    variants = {"whole tick, table only": {"twin": False}, "whole tick, table + twin": {"twin": True}}
    for name in variants:
        rows[name] = []
        if before_root is not None:
            rows[f"{name} (before)"] = []
    for _ in range(repeats):
        for name, between in zip(flat_names, (False, True), strict=True):
            wall, cpu = flat_tick(bundle, seconds, between)
            rows[name].append((np.median(wall), np.percentile(wall, 99), np.median(cpu), np.percentile(cpu, 99)))
        for name, variant in variants.items():
            rows[name] += [r[:4] for r in whole_tick(bundle, seconds, False, 1, **variant)]
            if before_root is not None:
                rows[f"{name} (before)"].append(lean_before(before_root, bundle, seconds, variant["twin"]))
    flat_wall = np.median([r[0] for r in rows["flat loop (reference)"]])
    flat_cpu = np.median([r[2] for r in rows["flat loop (reference)"]])
    for name, values in rows.items():
        wall_med, cpu_med = np.median([r[0] for r in values]), np.median([r[2] for r in values])
        wall_p99, cpu_p99 = np.median([r[1] for r in values]), np.median([r[3] for r in values])
        print(
            f"{name:<39} {wall_med:8.2f} {wall_p99:8.2f} {cpu_med:8.2f} {cpu_p99:8.2f} "
            f"{wall_med / flat_wall:7.2f} {cpu_med / flat_cpu:7.2f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="length of each real-time run")
    parser.add_argument("--skip-realtime", action="store_true")
    parser.add_argument("--before", type=Path, metavar="DIR", help="source tree of the pre-v2 runtime (commit 4df3193)")
    parser.add_argument("--repeats", type=int, default=3, help="runs per whole-tick row (default 3)")
    parser.add_argument("--compute-seconds", type=float, default=10.0, help="length of each whole-tick run")
    parser.add_argument("--rig-seconds", type=float, default=20.0, help="length of each run/record/probe run")
    parser.add_argument(
        "--only-rig-commands", type=int, metavar="N", help="only the run/record/probe table, N repeats (0: skip it)"
    )
    parser.add_argument("--only-live", type=int, metavar="N", help="only the with/without --live table, N repeats")
    parser.add_argument("--only-twin", type=int, metavar="N", help="only the forward-twin tick table, N repeats")
    parser.add_argument("--only-lean", type=int, metavar="N", help="only the whole tick vs the flat loop, N repeats")
    parser.add_argument(
        "--only-nets", type=int, metavar="N", help="only the LSTM-net feedforward and twin tick table, N repeats"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        bundle = make_bundle(Path(tmp))
        if args.only_rig_commands:
            rig_commands_cpu(bundle, args.rig_seconds, args.only_rig_commands)
            rig_commands_table(bundle, args.rig_seconds, args.only_rig_commands)
            return
        if args.only_live:
            live_table(bundle, args.rig_seconds, args.only_live)
            return
        if args.only_twin:
            twin_table(bundle, args.compute_seconds, args.only_twin)
            return
        if args.only_lean:
            lean_table(bundle, args.compute_seconds, args.only_lean, args.before)
            return
        if args.only_nets:
            nets_table(Path(tmp), args.compute_seconds, args.only_nets)
            return
        breakdown(bundle)
        compute_table(bundle, args.compute_seconds, args.repeats, args.before)
        if args.only_rig_commands is None or args.only_rig_commands > 0:
            rig_commands_cpu(bundle, args.rig_seconds, args.repeats)
            rig_commands_table(bundle, args.rig_seconds, args.repeats)
        live_table(bundle, args.rig_seconds, args.repeats)
        if args.skip_realtime:
            return
        print(f"\nReal-time 1 kHz over the serial DAQ (pty, HIL in another process), {args.seconds:g} s each")
        header = f"{'run':<26} {'median':>7} {'p99':>7} {'p99.9':>7} {'max':>8} {'overruns':>9} {'per 1e4':>8}"
        print(header + "   (lateness in us)")
        for fifo in (False, True):
            s = realtime_run(bundle, args.seconds, fifo)
            lat = s["lateness"]
            name = "Python, SCHED_FIFO" if fifo else "Python, SCHED_OTHER"
            print(
                f"{name:<26} {lat['lateness_median_us']:7.0f} {lat['lateness_p99_us']:7.0f} "
                f"{lat['lateness_p999_us']:7.0f} {lat['lateness_max_us']:8.0f} {lat['overruns']:9d} "
                f"{lat['overruns_per_10k']:8.2f}   faults {s['faults'] or 'none'}, RMS {s['rms_error']:.2f} mm"
            )
            if fifo:
                print(f"{'':<26} {'; '.join(s['realtime'])}")
        for fifo in (False, True):
            result = c_loop(fifo)
            name = "C, SCHED_FIFO" if fifo else "C, SCHED_OTHER"
            if result is None:
                print(f"{name:<26} (no C compiler or SCHED_FIFO refused)")
            else:
                print(
                    f"{name:<26} {'':>7} {'':>7} {'':>7} {result[1]:8d} {result[0]:9d} {result[0]:8.2f}   (1e4 ticks)"
                )


if __name__ == "__main__":
    main()
