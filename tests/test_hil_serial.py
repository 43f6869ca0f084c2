"""The serial DAQ protocol: codec, a real pseudo-terminal through pyserial, faults, real-time mode."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
import serial

from edge.devices.daq_protocol import (
    COMMAND_FORMAT,
    FLAG_VALVE_ENABLE,
    SAMPLE_FORMAT,
    FrameDecoder,
    FrameType,
    crc16_ccitt,
    encode_frame,
)
from hil.daq_server import DaqServer, open_pty
from hil.rig import HilRig


def test_crc_check_value():
    assert crc16_ccitt(b"123456789") == 0x29B1


def test_decoder_resynchronises_after_garbage_and_bad_crc():
    good = encode_frame(7, FrameType.COMMAND, COMMAND_FORMAT.pack(100, 1))
    bad = bytearray(encode_frame(8, FrameType.COMMAND, COMMAND_FORMAT.pack(5, 0)))
    bad[-1] ^= 0xFF
    decoder = FrameDecoder()
    frames = decoder.feed(b"\x00\xa5junk" + bytes(bad) + good[:5]) + decoder.feed(good[5:])
    assert [(f.sequence, f.frame_type) for f in frames] == [(7, FrameType.COMMAND)]
    assert decoder.crc_errors == 1 and decoder.dropped_bytes > 0


@pytest.fixture
def lockstep_daq():
    rig = HilRig()
    master, path = open_pty()
    port = serial.Serial(path, baudrate=921600, timeout=0)
    server = DaqServer(rig, master, rate_hz=1000.0)
    yield rig, server, port
    port.close()
    os.close(master)


def run(rig, server, port, seconds, decoder):
    """Advance the lockstep rig 1 ms at a time, serving the DAQ and reading the pty."""
    frames = []
    for _ in range(int(seconds * 1000)):
        rig.clock.advance(1e-3)
        server.service()
        frames += decoder.feed(port.read(4096))
    return frames


def test_command_and_samples_round_trip_over_a_pty(lockstep_daq):
    rig, server, port = lockstep_daq
    server.command_timeout_s = 10.0  # one command, held for a second
    decoder = FrameDecoder()
    port.write(encode_frame(1, FrameType.COMMAND, COMMAND_FORMAT.pack(round(3.0 / 10.0 * 4096), FLAG_VALVE_ENABLE)))
    port.flush()
    frames = run(rig, server, port, 1.0, decoder)
    samples = [SAMPLE_FORMAT.unpack(f.payload) for f in frames if f.frame_type == FrameType.SAMPLE]
    assert len(samples) >= 990 and decoder.crc_errors == 0
    sequences = [f.sequence for f in frames]
    assert sequences == list(range(sequences[0], sequences[0] + len(sequences)))
    t_us, pressure_code, _, status = samples[-1]
    pressure = (pressure_code / 32768 * 4.096 - 0.5) / 0.4
    assert pressure == pytest.approx(3.0, abs=0.05) and status & 0x02
    assert server.commands == 1


def test_the_daq_vents_by_itself_when_commands_stop(lockstep_daq):
    rig, server, port = lockstep_daq
    port.write(encode_frame(1, FrameType.COMMAND, COMMAND_FORMAT.pack(2000, FLAG_VALVE_ENABLE)))
    port.flush()
    run(rig, server, port, 0.05, FrameDecoder())
    assert rig.gpio.get("valve_enable")
    run(rig, server, port, server.command_timeout_s, FrameDecoder())
    assert not rig.gpio.get("valve_enable") and server.command_timeouts == 1


def test_serial_faults_are_visible_at_the_wire(lockstep_daq):
    rig, server, port = lockstep_daq
    decoder = FrameDecoder()
    run(rig, server, port, 0.05, decoder)
    server.faults.corrupt_frames = 3
    frames = run(rig, server, port, 0.05, decoder)
    assert decoder.crc_errors == 3
    server.faults.drop_frames = 5
    frames = frames[-1:] + run(rig, server, port, 0.05, decoder)
    gaps = [b.sequence - a.sequence for a, b in zip(frames, frames[1:])]
    assert max(gaps) == 6
    server.faults.delay_s = 0.02
    before = len(run(rig, server, port, 0.019, decoder))
    assert before == 0  # everything held back for 20 ms
    assert len(run(rig, server, port, 0.03, decoder)) >= 25


def test_real_time_mode_in_another_process():
    process = subprocess.Popen(
        [sys.executable, "-m", "host.cli", "hil", "serve", "--duration", "20"],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        line = process.stdout.readline()
        assert line.startswith("pty: ")
        port = serial.Serial(line.split()[1], timeout=0.05)
        decoder = FrameDecoder()
        frames = []
        started = time.monotonic()
        while time.monotonic() - started < 1.0:
            frames += decoder.feed(port.read(4096))
        port.close()
        stamps = [SAMPLE_FORMAT.unpack(f.payload)[0] for f in frames]
        assert len(frames) > 700  # ~1 kHz on the wall clock, minus start-up
        assert decoder.crc_errors == 0
        assert max(b - a for a, b in zip(stamps, stamps[1:])) < 50_000  # no gap above 50 ms
    finally:
        process.send_signal(signal.SIGTERM)
        out, _ = process.communicate(timeout=10)
    assert process.returncode == 0 and "served" in out
