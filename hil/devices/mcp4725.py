"""Register-level emulator of the Microchip MCP4725 12-bit DAC.

Commands (first byte): fast mode ``00 PD1 PD0 D11..D8`` + ``D7..D0`` (pairs may repeat);
write DAC register ``010x xPD1PD0x`` + ``D11..D4`` + ``D3..D0 0000``; write DAC register and
EEPROM ``011x xPD1PD0x`` + the same (EEPROM busy for 25 ms: RDY reads 0 and further writes
are ignored). A read returns status (RDY bit 7, POR bit 6, PD bits 2:1), the DAC register
(two bytes, left-aligned) and the EEPROM (PD bits 6:5 + D11..D8, D7..D0). Output voltage is
``VDD * code / 4096``, or 0 V in any power-down mode.
"""

from __future__ import annotations

from collections.abc import Callable

EEPROM_WRITE_S = 0.025


class MCP4725Emulator:
    """Emulated DAC.

    Args:
        now: the clock (seconds).
        vdd: supply and reference voltage [V].
        eeprom_code: power-on value of the DAC register.
    """

    def __init__(self, now: Callable[[], float], vdd: float = 5.0, eeprom_code: int = 0) -> None:
        self._now = now
        self.vdd = vdd
        self.code = eeprom_code & 0xFFF
        self.power_down = 0
        self.eeprom_code = eeprom_code & 0xFFF
        self.eeprom_power_down = 0
        self._eeprom_busy_until = -1.0
        self.stuck = False  # fault: the output ignores writes

    @property
    def ready(self) -> bool:
        return self._now() >= self._eeprom_busy_until

    @property
    def output_volts(self) -> float:
        return 0.0 if self.power_down else self.vdd * self.code / 4096.0

    def write(self, payload: bytes) -> None:
        if not payload or not self.ready or self.stuck:
            return
        command = payload[0] >> 5
        if payload[0] >> 6 == 0:  # fast mode: pairs of bytes
            for i in range(0, len(payload) - 1, 2):
                self.power_down = (payload[i] >> 4) & 0x3
                self.code = ((payload[i] & 0x0F) << 8) | payload[i + 1]
            return
        if command in (0b010, 0b011) and len(payload) >= 3:
            self.power_down = (payload[0] >> 1) & 0x3
            self.code = (payload[1] << 4) | (payload[2] >> 4)
            if command == 0b011:
                self.eeprom_code, self.eeprom_power_down = self.code, self.power_down
                self._eeprom_busy_until = self._now() + EEPROM_WRITE_S

    def read(self, length: int) -> bytes:
        status = (0x80 if self.ready else 0x00) | 0x40 | (self.power_down << 1)
        data = bytes(
            (
                status,
                self.code >> 4,
                (self.code & 0x0F) << 4,
                (self.eeprom_power_down << 5) | (self.eeprom_code >> 8),
                self.eeprom_code & 0xFF,
            )
        )
        return data[:length] + bytes(max(0, length - len(data)))
