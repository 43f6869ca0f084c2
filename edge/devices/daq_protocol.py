"""Framed binary protocol of the serial DAQ link (documented in docs/serial-daq.md).

Frame: ``A5 5A | len | seq (u16 LE) | type | payload | crc (u16 LE)``, where ``len`` counts
``seq + type + payload`` (3 + payload bytes) and the CRC-16/CCITT-FALSE (poly 0x1021, init
0xFFFF) covers ``len`` through the payload. The decoder resynchronises on the next ``A5 5A``
after a bad CRC or length and counts what it dropped.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from enum import IntEnum

SYNC = b"\xa5\x5a"
MAX_PAYLOAD = 64


class FrameType(IntEnum):
    SAMPLE = 0x01  # DAQ -> host: t_us u32, pressure i16, displacement i16, status u8
    COMMAND = 0x02  # host -> DAQ: dac code u16 (0..4095), flags u8 (bit 0: valve enable)
    CONFIG = 0x03  # host -> DAQ: sample rate u16 [Hz]


SAMPLE_FORMAT = struct.Struct("<IhhB")
COMMAND_FORMAT = struct.Struct("<HB")
CONFIG_FORMAT = struct.Struct("<H")

SENSOR_FULL_SCALE_V = 4.096  # the DAQ's 16-bit converter spans +-4.096 V


def sensor_code(volts: float) -> int:
    """A voltage as the DAQ's converter reports it (saturating at the 16-bit limits)."""
    return min(max(round(volts / SENSOR_FULL_SCALE_V * 32768), -32768), 32767)


def sensor_volts(code: int) -> float:
    """A SAMPLE frame's sensor code back in volts."""
    return code / 32768.0 * SENSOR_FULL_SCALE_V


STATUS_ESTOP = 0x01
STATUS_VALVE_ENABLED = 0x02
FLAG_VALVE_ENABLE = 0x01


def _crc_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
        table.append(crc)
    return tuple(table)


_CRC_TABLE = _crc_table()


def crc16_ccitt(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/CCITT-FALSE, table driven (check value of ``b"123456789"`` is 0x29B1)."""
    table = _CRC_TABLE
    for byte in data:
        crc = ((crc << 8) & 0xFFFF) ^ table[(crc >> 8) ^ byte]
    return crc


def encode_frame(sequence: int, frame_type: int, payload: bytes) -> bytes:
    """One frame, ready for the wire."""
    if len(payload) > MAX_PAYLOAD:
        raise ValueError(f"payload of {len(payload)} bytes exceeds {MAX_PAYLOAD}")
    body = bytes((len(payload) + 3,)) + struct.pack("<HB", sequence & 0xFFFF, frame_type) + payload
    return SYNC + body + struct.pack("<H", crc16_ccitt(body))


@dataclass(frozen=True)
class Frame:
    sequence: int
    frame_type: int
    payload: bytes


class FrameDecoder:
    """Incremental decoder: ``feed(bytes) -> [Frame]``; bad frames are counted and skipped."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self.crc_errors = 0
        self.dropped_bytes = 0

    def feed(self, data: bytes) -> list[Frame]:
        self._buffer.extend(data)
        frames: list[Frame] = []
        buffer = self._buffer
        while True:
            start = buffer.find(SYNC)
            if start < 0:
                keep = 1 if buffer.endswith(SYNC[:1]) else 0
                self.dropped_bytes += len(buffer) - keep
                del buffer[: len(buffer) - keep]
                return frames
            if start:
                self.dropped_bytes += start
                del buffer[:start]
            if len(buffer) < 3:
                return frames
            length = buffer[2]
            if not 3 <= length <= MAX_PAYLOAD + 3:
                self.crc_errors += 1
                del buffer[:2]
                continue
            total = 2 + 1 + length + 2
            if len(buffer) < total:
                return frames
            body = bytes(buffer[2 : 3 + length])
            (crc,) = struct.unpack_from("<H", buffer, 3 + length)
            if crc != crc16_ccitt(body):
                self.crc_errors += 1
                del buffer[:2]
                continue
            sequence, frame_type = struct.unpack_from("<HB", body, 1)
            frames.append(Frame(sequence, frame_type, body[4:]))
            del buffer[:total]
