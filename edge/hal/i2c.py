"""The I2C port: one call, ``transfer(address, messages)`` (python-periphery's shape).

A transfer is one combined transaction: the messages run in order with repeated starts and a
single stop, as Linux ``I2C_RDWR`` does. A write message carries its bytes; a read message is
filled in place. Any failure (address NACK, data NACK, I/O error) raises
:class:`~edge.errors.BusError` with the errno of the kernel (``ENXIO``, ``EREMOTEIO``, ``EIO``).
"""

from __future__ import annotations

import errno
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from edge.errors import BusError


@dataclass
class I2CMessage:
    """One message of a transfer: ``data`` to write, or a buffer of ``len(data)`` to read into."""

    data: bytearray
    read: bool = False

    @classmethod
    def write(cls, payload: bytes | bytearray | Sequence[int]) -> I2CMessage:
        return cls(bytearray(payload), read=False)

    @classmethod
    def read_bytes(cls, length: int) -> I2CMessage:
        return cls(bytearray(length), read=True)


class I2CBus(Protocol):
    """What a driver needs of an I2C bus."""

    def transfer(self, address: int, messages: Sequence[I2CMessage]) -> None:
        """Run ``messages`` as one transaction with the device at 7-bit ``address``."""

    def close(self) -> None:
        """Release the bus."""


BITS_PER_BYTE = 9  # 8 data bits + acknowledge
START_STOP_BITS = 2


def transfer_bits(messages: Sequence[I2CMessage]) -> int:
    """Clock cycles of one transfer: each message is an address byte plus its data bytes."""
    return sum(1 + len(m.data) for m in messages) * BITS_PER_BYTE + START_STOP_BITS


def check_address(address: int) -> None:
    """7-bit addresses only; the reserved ranges are refused."""
    if not 0x08 <= address <= 0x77:
        raise BusError(errno.EINVAL, f"I2C address 0x{address:02x} outside 0x08..0x77")


class SMBus2I2C:
    """Linux backend: ``/dev/i2c-N`` through smbus2's ``i2c_rdwr`` (the ``I2C_RDWR`` ioctl).

    Args:
        device: bus number (``1``) or device path (``/dev/i2c-1``).
    """

    def __init__(self, device: int | str) -> None:
        from smbus2 import SMBus  # imported here: the port is usable without smbus2 installed

        number = int(str(device).rsplit("-", 1)[-1]) if isinstance(device, str) else device
        try:
            self._bus = SMBus(number)
        except OSError as exc:
            raise BusError(
                exc.errno,
                f"cannot open /dev/i2c-{number}: {exc.strerror}; check the "
                "bus number and that the i2c-dev module is loaded",
            ) from exc

    def transfer(self, address: int, messages: Sequence[I2CMessage]) -> None:
        from smbus2 import i2c_msg

        check_address(address)
        native = [
            i2c_msg.read(address, len(m.data)) if m.read else i2c_msg.write(address, bytes(m.data)) for m in messages
        ]
        try:
            self._bus.i2c_rdwr(*native)
        except OSError as exc:
            raise BusError(exc.errno, f"I2C transfer to 0x{address:02x} failed: {exc.strerror}") from exc
        for message, raw in zip(messages, native):
            if message.read:
                message.data[:] = bytes(raw)

    def close(self) -> None:
        self._bus.close()
