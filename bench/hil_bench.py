"""Benchmark of the HIL emulator: how much faster than real time it runs.

Usage: python bench/hil_bench.py

Rows: the plant alone (1 kHz fixed step); a lockstep tick of the rig as an edge driver would
use it (DAC fast write + ADC conversion read over the emulated I2C bus + 1 ms of simulated
time); the recorder (mixed scenario, sensors sampled at 100 Hz); the DAQ server over a real
pseudo-terminal (1 kHz SAMPLE frames read back through pyserial every 10 ms; reading every
1 ms adds ~33 us of pyserial select per read). Target: >= 50x real time at a 1 kHz plant step.
"""

from __future__ import annotations

import os
import time

import numpy as np
import serial

from edge.devices.daq_protocol import FrameDecoder
from edge.hal.i2c import I2CMessage
from hil.daq_server import DaqServer, open_pty
from hil.plant import PlantParams, simulate
from hil.record import record
from hil.rig import ADC_ADDRESS, DAC_ADDRESS, HilRig

SECONDS = 20.0


def plant_only() -> float:
    t = np.arange(0, SECONDS, 1e-3)
    start = time.perf_counter()
    simulate(2.0 + 1.5 * np.sin(2 * np.pi * 0.5 * t), PlantParams())
    return time.perf_counter() - start


def lockstep_ticks() -> float:
    rig = HilRig(adc_variant="ADS1015")
    rig.gpio.set("valve_enable", True)
    bus = rig.bus
    bus.transfer(ADC_ADDRESS, [I2CMessage.write([1, 0x42, 0xC3])])  # AIN0, +-4.096 V, continuous, 3300 SPS
    reply = I2CMessage.read_bytes(2)
    start = time.perf_counter()
    for k in range(int(SECONDS * 1000)):
        code = int(2048 + 1500 * np.sin(2 * np.pi * 0.5 * k / 1000.0))
        bus.transfer(DAC_ADDRESS, [I2CMessage.write([code >> 8, code & 0xFF])])
        bus.transfer(ADC_ADDRESS, [I2CMessage.write([0]), reply])
        rig.clock.advance(1e-3)
    return time.perf_counter() - start


def recorder() -> float:
    start = time.perf_counter()
    record("mixed", 0, SECONDS)
    return time.perf_counter() - start


def daq_over_pty() -> float:
    rig = HilRig()
    master, path = open_pty()
    port = serial.Serial(path, timeout=0)
    server = DaqServer(rig, master)
    decoder = FrameDecoder()
    received = 0
    start = time.perf_counter()
    for tick in range(int(SECONDS * 1000)):
        rig.clock.advance(1e-3)
        server.service()
        if tick % 10 == 9:  # the reader drains every 10 ms (170 bytes), as a batching reader would
            received += len(decoder.feed(port.read(4096)))
    received += len(decoder.feed(port.read(4096)))
    elapsed = time.perf_counter() - start
    port.close()
    os.close(master)
    assert received >= SECONDS * 1000 - 5, received
    return elapsed


def main() -> int:
    print(f"{'path':<44} {'simulated s':>12} {'wall s':>8} {'x real time':>12} {'us / ms tick':>13}")
    for name, run in (
        ("plant alone (1 kHz step)", plant_only),
        ("rig lockstep tick: DAC write + ADC read", lockstep_ticks),
        ("recorder: mixed scenario, 100 Hz sensors", recorder),
        ("DAQ server over a pty, 1 kHz frames", daq_over_pty),
    ):
        wall = run()
        print(f"{name:<44} {SECONDS:>12.1f} {wall:>8.2f} {SECONDS / wall:>12.1f} {wall / SECONDS * 1e3:>13.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
