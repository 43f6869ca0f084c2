"""The serial DAQ of the emulated rig, served on a pseudo-terminal.

The DAQ samples the pressure and displacement sensors with its own 16-bit converter (codes:
``edge.devices.daq_protocol.sensor_code``, saturating) at the configured rate, streams SAMPLE
frames, and applies COMMAND frames (DAC code and valve enable) and CONFIG frames (sample rate)
as they arrive. Like DAQ firmware, it vents the valve by itself when no COMMAND frame came for
``command_timeout_s`` (the host died or the cable came out). ``open_pty()`` gives a master
descriptor for the server and the slave path the edge opens with pyserial, exactly as it would
open ``/dev/ttyUSB0``.

Faults on the wire (:class:`SerialFaults`): corrupt a byte of the next N frames, drop the next
N frames, hold frames back by a delay.
"""

from __future__ import annotations

import errno
import os
import tty
from dataclasses import dataclass, field

from edge.devices.daq_protocol import (
    COMMAND_FORMAT,
    CONFIG_FORMAT,
    FLAG_VALVE_ENABLE,
    SAMPLE_FORMAT,
    STATUS_ESTOP,
    STATUS_VALVE_ENABLED,
    FrameDecoder,
    FrameType,
    encode_frame,
    sensor_code,
)
from hil.rig import DISPLACEMENT_CHANNEL, PRESSURE_CHANNEL, HilRig


def open_pty() -> tuple[int, str]:
    """A raw, non-blocking pseudo-terminal: ``(master fd, slave path)``."""
    master, slave = os.openpty()
    tty.setraw(slave)
    path = os.ttyname(slave)
    os.set_blocking(master, False)
    os.close(slave)  # the edge opens it by path; keeping it open here would mask hang-ups
    return master, path


@dataclass
class SerialFaults:
    corrupt_frames: int = 0
    drop_frames: int = 0
    delay_s: float = 0.0
    log: list[str] = field(default_factory=list)


class DaqServer:
    """Serves the DAQ protocol for ``rig`` on descriptor ``fd`` (call :meth:`service` often)."""

    def __init__(self, rig: HilRig, fd: int, rate_hz: float = 1000.0, command_timeout_s: float = 0.1) -> None:
        self.rig = rig
        self.command_timeout_s = command_timeout_s
        self._last_command = rig.clock.now()
        self.command_timeouts = 0
        self.fd = fd
        self.rate_hz = rate_hz
        self.faults = SerialFaults()
        self._decoder = FrameDecoder()
        self._sequence = 0
        self._next_sample = rig.clock.now()
        self._held: list[tuple[float, bytes]] = []
        self.sent = 0
        self.overruns = 0  # frames the reader did not take in time (pty buffer full)
        self.commands = 0

    def service(self) -> None:
        """Apply received commands, then send every sample that has come due."""
        self._receive()
        now = self.rig.clock.now()
        if self.rig.gpio.level("valve_enable") and now - self._last_command > self.command_timeout_s:
            self.rig.sync()
            self.rig.gpio.set("valve_enable", False)
            self.command_timeouts += 1
        while self._next_sample <= now:
            self._queue(self._sample_frame(self._next_sample))
            self._next_sample += 1.0 / self.rate_hz
        self._flush(now)

    def _receive(self) -> None:
        while True:
            try:
                data = os.read(self.fd, 4096)
            except BlockingIOError:
                return
            except OSError as exc:
                if exc.errno == errno.EIO:  # nobody has the slave open
                    return
                raise
            if not data:
                return
            for frame in self._decoder.feed(data):
                self._apply(frame.frame_type, frame.payload)

    def _apply(self, frame_type: int, payload: bytes) -> None:
        rig = self.rig
        if frame_type == FrameType.COMMAND and len(payload) == COMMAND_FORMAT.size:
            code, flags = COMMAND_FORMAT.unpack(payload)
            rig.sync()  # the old command held until now
            if not rig.dac.stuck:
                rig.dac.code, rig.dac.power_down = min(code, 4095), 0
            rig.gpio.set("valve_enable", bool(flags & FLAG_VALVE_ENABLE))
            self.commands += 1
            self._last_command = rig.clock.now()
        elif frame_type == FrameType.CONFIG and len(payload) == CONFIG_FORMAT.size:
            (rate,) = CONFIG_FORMAT.unpack(payload)
            if rate:
                self.rate_hz = float(rate)

    def _sample_frame(self, t: float) -> bytes:
        rig = self.rig
        status = (STATUS_ESTOP if rig.gpio.level("estop") else 0) | (
            STATUS_VALVE_ENABLED if rig.gpio.level("valve_enable") else 0
        )
        payload = SAMPLE_FORMAT.pack(
            int(round(t * 1e6)) & 0xFFFFFFFF,
            sensor_code(rig.analog_volts(PRESSURE_CHANNEL)),
            sensor_code(rig.analog_volts(DISPLACEMENT_CHANNEL)),
            status,
        )
        frame = encode_frame(self._sequence, FrameType.SAMPLE, payload)
        self._sequence = (self._sequence + 1) & 0xFFFF
        return frame

    def _queue(self, frame: bytes) -> None:
        faults = self.faults
        if faults.drop_frames:
            faults.drop_frames -= 1
            faults.log.append("drop")
            return
        if faults.corrupt_frames:
            faults.corrupt_frames -= 1
            faults.log.append("corrupt")
            frame = frame[:6] + bytes((frame[6] ^ 0x5A,)) + frame[7:]
        self._held.append((self.rig.clock.now() + faults.delay_s, frame))

    def _flush(self, now: float) -> None:
        ready = [frame for due, frame in self._held if due <= now]
        self._held = [(due, frame) for due, frame in self._held if due > now]
        for frame in ready:
            try:
                os.write(self.fd, frame)
                self.sent += 1
            except BlockingIOError:
                self.overruns += 1
            except OSError as exc:
                if exc.errno != errno.EIO:
                    raise
                self.overruns += 1
