"""An emulated I2C bus implementing :class:`edge.hal.i2c.I2CBus`, with faults on the wire.

Devices attach at an address and see the bytes exactly as a real chip would: each write
message's payload, and read requests of a given length. Faults (pymodbus's manipulator idea):
NACK and EIO bursts for the next N transfers (optionally for one address only) and an added
latency per transfer, which a simulated clock lets pass. With ``bus_hz`` the wire time of every
transfer (9 clocks per byte) passes too, so a lockstep run pays for the bus as a real one does.
"""

from __future__ import annotations

import errno
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

from edge.errors import BusError
from edge.hal.i2c import I2CMessage, check_address, transfer_bits


class I2CDevice(Protocol):
    def write(self, payload: bytes) -> None: ...

    def read(self, length: int) -> bytes: ...


@dataclass
class WireFaults:
    """Faults the next transfers will meet; ``log`` records every one that fired."""

    nack_remaining: int = 0
    eio_remaining: int = 0
    only_address: int | None = None
    latency_s: float = 0.0
    log: list[str] = field(default_factory=list)

    def nack_burst(self, transfers: int, address: int | None = None) -> None:
        self.nack_remaining, self.only_address = transfers, address

    def eio_burst(self, transfers: int, address: int | None = None) -> None:
        self.eio_remaining, self.only_address = transfers, address


class EmulatedI2CBus:
    """Emulated bus.

    Args:
        advance: called with the latency of each transfer (a simulated clock's ``advance``).
        before_transfer: called before each transfer (the rig brings its physics up to date).
        bus_hz: SCL frequency; when given, each transfer's wire time is passed to ``advance``.
    """

    def __init__(
        self,
        advance: Callable[[float], None] | None = None,
        before_transfer: Callable[[], None] | None = None,
        faults: WireFaults | None = None,
        bus_hz: float | None = None,
    ) -> None:
        self.devices: dict[int, I2CDevice] = {}
        self.faults = faults or WireFaults()
        self.transfers = 0
        self._advance = advance
        self._before = before_transfer
        self.bus_hz = bus_hz

    def attach(self, address: int, device: I2CDevice) -> None:
        check_address(address)
        self.devices[address] = device

    def transfer(self, address: int, messages: Sequence[I2CMessage]) -> None:
        check_address(address)
        self.transfers += 1
        faults = self.faults
        if self._advance is not None:
            wire_s = transfer_bits(messages) / self.bus_hz if self.bus_hz else 0.0
            if faults.latency_s or wire_s:
                self._advance(faults.latency_s + wire_s)
        targeted = faults.only_address in (None, address)
        if faults.nack_remaining and targeted:
            faults.nack_remaining -= 1
            faults.log.append(f"nack 0x{address:02x}")
            raise BusError(errno.EREMOTEIO, f"I2C 0x{address:02x}: no acknowledge (injected)")
        if faults.eio_remaining and targeted:
            faults.eio_remaining -= 1
            faults.log.append(f"eio 0x{address:02x}")
            raise BusError(errno.EIO, f"I2C 0x{address:02x}: I/O error (injected)")
        device = self.devices.get(address)
        if device is None:
            raise BusError(errno.ENXIO, f"I2C 0x{address:02x}: no device acknowledges this address")
        if self._before is not None:
            self._before()
        for message in messages:
            if message.read:
                message.data[:] = device.read(len(message.data))
            else:
                device.write(bytes(message.data))

    def close(self) -> None:
        """Nothing to release."""
