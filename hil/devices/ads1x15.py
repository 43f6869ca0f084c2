"""Register-level emulator of the TI ADS1115 (16 bit) and ADS1015 (12 bit) ADCs.

Registers (pointer byte 0-3): conversion, config (reset 0x8583), Lo_thresh (0x8000),
Hi_thresh (0x7FFF). Config fields: OS[15] (write 1: start a single conversion; read: 0 while
converting), MUX[14:12], PGA[11:9] (+-6.144 .. 0.256 V), MODE[8] (1 single-shot), DR[7:5],
comparator bits (stored, not acted on). A conversion takes one data-rate period; the result is
the input at the moment the conversion is first observed after completing (at most one period
later than the chip's own sample instant). Codes are two's complement and saturate at 0x7FFF /
0x8000 (ADS1015: 12-bit codes left-aligned, 0x7FF0 / 0x8000). Inputs are limited to the
chip's absolute range (GND - 0.3 V .. VDD + 0.3 V).
"""

from __future__ import annotations

from collections.abc import Callable

FULL_SCALE_V = (6.144, 4.096, 2.048, 1.024, 0.512, 0.256, 0.256, 0.256)
DATA_RATES = {
    "ADS1115": (8, 16, 32, 64, 128, 250, 475, 860),
    "ADS1015": (128, 250, 490, 920, 1600, 2400, 3300, 3300),
}
MUX_PAIRS = ((0, 1), (0, 3), (1, 3), (2, 3), (0, None), (1, None), (2, None), (3, None))
CONFIG_RESET = 0x8583


class ADS1x15Emulator:
    """Emulated ADC.

    Args:
        now: the clock (seconds).
        analog: ``analog(channel) -> volts`` for AIN0..AIN3 at the current time.
        variant: ``"ADS1115"`` or ``"ADS1015"``.
        vdd: supply voltage [V].
    """

    def __init__(
        self, now: Callable[[], float], analog: Callable[[int], float], variant: str = "ADS1115", vdd: float = 3.3
    ) -> None:
        if variant not in DATA_RATES:
            raise ValueError(f"variant {variant!r} unknown; use ADS1115 or ADS1015")
        self.variant = variant
        self._now = now
        self._analog = analog
        self._vdd = vdd
        self.registers = [0x0000, CONFIG_RESET, 0x8000, 0x7FFF]
        self._pointer = 0
        self._busy_until: float | None = None  # single-shot conversion in progress
        self._continuous_since: float | None = None
        self._last_continuous = -1
        self.stuck_busy = False  # fault: the OS bit never reports a finished conversion

    def conversion_time(self, config: int | None = None) -> float:
        """Seconds per conversion at the configured data rate."""
        config = self.registers[1] if config is None else config
        return 1.0 / DATA_RATES[self.variant][(config >> 5) & 0x7]

    def _code(self, config: int) -> int:
        positive, negative = MUX_PAIRS[(config >> 12) & 0x7]

        def limited(channel: int) -> float:
            return min(max(self._analog(channel), -0.3), self._vdd + 0.3)

        volts = limited(positive) - (limited(negative) if negative is not None else 0.0)
        full_scale = FULL_SCALE_V[(config >> 9) & 0x7]
        if self.variant == "ADS1115":
            return min(max(round(volts / full_scale * 32768), -32768), 32767) & 0xFFFF
        return (min(max(round(volts / full_scale * 2048), -2048), 2047) << 4) & 0xFFFF

    def _update(self) -> None:
        now = self._now()
        config = self.registers[1]
        if self._busy_until is not None and now >= self._busy_until:
            self.registers[0] = self._code(config)
            self._busy_until = None
        if self._continuous_since is not None:
            completed = int((now - self._continuous_since) / self.conversion_time(config))
            if completed > self._last_continuous and completed >= 1:
                self.registers[0] = self._code(config)
                self._last_continuous = completed

    def _converting(self) -> bool:
        return self.stuck_busy or self._busy_until is not None or self._continuous_since is not None

    def write(self, payload: bytes) -> None:
        self._update()
        if not payload:
            return
        self._pointer = payload[0] & 0x03
        if len(payload) < 3:
            return
        value = (payload[1] << 8) | payload[2]
        if self._pointer == 0:
            return  # the conversion register is read-only
        if self._pointer != 1:
            self.registers[self._pointer] = value
            return
        self.registers[1] = value & 0x7FFF  # OS is not stored: it is an action / status bit
        if value & 0x0100:  # single-shot / power-down
            self._continuous_since = None
            if value & 0x8000 and self._busy_until is None:
                self._busy_until = self._now() + self.conversion_time(value)
        else:
            self._busy_until = None
            self._continuous_since = self._now()
            self._last_continuous = 0

    def read(self, length: int) -> bytes:
        self._update()
        value = self.registers[self._pointer]
        if self._pointer == 1:
            value = (value & 0x7FFF) | (0 if self._converting() else 0x8000)
        data = bytes(((value >> 8) & 0xFF, value & 0xFF))
        return (data * ((length + 1) // 2))[:length]
