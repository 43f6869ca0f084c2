"""Client of the serial DAQ (protocol in ``docs/serial-daq.md``), written against the serial
and clock ports.

The DAQ streams samples on its own clock; each tick takes the newest sample that has arrived
and does not wait for a new one (two free-running 1 kHz clocks would otherwise make every tick
wait up to a period for the DAQ's phase). A sample older than ``timeout_s`` is not used: the
tick waits for a fresh one until that age, and then it is a :class:`~edge.errors.BusError`
(the supervisor trips after a streak). Repeated and lost samples are counted.
"""

from __future__ import annotations

import errno
from dataclasses import dataclass

from edge.devices.daq_protocol import (
    COMMAND_FORMAT,
    CONFIG_FORMAT,
    FLAG_VALVE_ENABLE,
    SAMPLE_FORMAT,
    STATUS_ESTOP,
    FrameDecoder,
    FrameType,
    encode_frame,
    sensor_volts,
)
from edge.errors import BusError
from edge.hal.clock import Clock
from edge.hal.serial import SerialLink


@dataclass(frozen=True)
class DaqSample:
    """One sample: DAQ time [us, wraps], sensor voltages [V], e-stop line."""

    t_us: int
    pressure_volts: float
    displacement_volts: float
    estop: bool
    sequence: int


class DaqClient:
    """The edge end of the DAQ link.

    Args:
        link: the serial port.
        clock: deadlines for waits.
        sample_rate_hz: rate to ask the DAQ for.
        timeout_s: longest wait for a fresh sample per tick.
    """

    def __init__(self, link: SerialLink, clock: Clock, sample_rate_hz: int = 1000, timeout_s: float = 0.002) -> None:
        self._link, self._clock = link, clock
        self.timeout_s = timeout_s
        self._decoder = FrameDecoder()
        self._sequence = 0
        self._latest: DaqSample | None = None
        self._received_at = -float("inf")
        self._returned: DaqSample | None = None
        self.samples = 0
        self.lost_samples = 0
        self.repeated_samples = 0
        self._send(FrameType.CONFIG, CONFIG_FORMAT.pack(sample_rate_hz))

    @property
    def crc_errors(self) -> int:
        return self._decoder.crc_errors

    def _send(self, frame_type: int, payload: bytes) -> None:
        self._link.write(encode_frame(self._sequence, frame_type, payload))
        self._sequence = (self._sequence + 1) & 0xFFFF

    def _take(self) -> None:
        for frame in self._decoder.feed(self._link.read_available()):
            if frame.frame_type != FrameType.SAMPLE or len(frame.payload) != SAMPLE_FORMAT.size:
                continue
            t_us, pressure, displacement, status = SAMPLE_FORMAT.unpack(frame.payload)
            sample = DaqSample(
                t_us,
                sensor_volts(pressure),
                sensor_volts(displacement),
                bool(status & STATUS_ESTOP),
                frame.sequence,
            )
            if self._latest is not None:
                self.lost_samples += (frame.sequence - self._latest.sequence - 1) & 0xFFFF
            self.samples += 1
            self._latest = sample
            self._received_at = self._clock.now()

    def read(self) -> DaqSample:
        """The newest sample, if it is at most ``timeout_s`` old; else wait for one until then."""
        self._take()
        while self._clock.now() - self._received_at > self.timeout_s:
            if not self._link.wait_readable(self.timeout_s):
                raise BusError(
                    errno.ETIMEDOUT,
                    f"serial DAQ: no valid sample for {self.timeout_s * 1e3:.1f} ms "
                    f"({self.crc_errors} CRC errors so far); check the cable and the DAQ",
                )
            self._take()
        sample = self._latest
        assert sample is not None
        if sample is self._returned:
            self.repeated_samples += 1
        self._returned = sample
        return sample

    def command(self, dac_code: int, valve_enable: bool) -> None:
        """Send the valve command: 12-bit DAC code and the enable flag (off vents)."""
        code = min(4095, max(0, int(dac_code)))
        self._send(FrameType.COMMAND, COMMAND_FORMAT.pack(code, FLAG_VALVE_ENABLE if valve_enable else 0))
