"""Driver for the Microchip MCP4725 12-bit DAC, written against the I2C port."""

from __future__ import annotations

from edge.hal.i2c import I2CBus, I2CMessage, transfer_bits


class MCP4725:
    """One MCP4725.

    Args:
        bus: the I2C port.
        address: 7-bit address (0x60..0x67).
        vdd: supply = reference voltage [V].
    """

    def __init__(self, bus: I2CBus, *, address: int = 0x60, vdd: float = 5.0) -> None:
        self._bus, self.address, self.vdd = bus, address, vdd
        self._message = I2CMessage.write([0, 0])

    @staticmethod
    def write_bus_bits() -> int:
        """I2C clocks of one fast-mode write."""
        return transfer_bits([I2CMessage.write([0, 0])])

    def write_code(self, code: int) -> None:
        """Fast-mode write of a 12-bit code (0..4095), output enabled."""
        if not 0 <= code <= 4095:
            raise ValueError(f"DAC code {code} outside 0..4095")
        data = self._message.data
        data[0], data[1] = (code >> 8) & 0x0F, code & 0xFF
        self._bus.transfer(self.address, [self._message])

    def write_volts(self, volts: float) -> int:
        """Nearest code for ``volts``, clamped to 0..VDD; returns the code written."""
        code = min(4095, max(0, round(volts / self.vdd * 4096)))
        self.write_code(code)
        return code

    def power_down(self) -> None:
        """Output off (1 kOhm to ground): the safe state of a valve command."""
        self._bus.transfer(self.address, [I2CMessage.write([0x40 | (0b01 << 1), 0x00, 0x00])])

    def read_code(self) -> int:
        """The DAC register as the chip reports it."""
        reply = I2CMessage.read_bytes(3)
        self._bus.transfer(self.address, [reply])
        return (reply.data[1] << 4) | (reply.data[2] >> 4)
