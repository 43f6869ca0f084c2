"""Driver for the TI ADS1115 / ADS1015 ADC, written against the I2C and clock ports.

Single-shot reads start a conversion, wait one conversion period on the clock, then poll the
OS bit with a deadline: a dead or stuck chip raises :class:`~edge.errors.BusError`
(``ETIMEDOUT``) instead of stalling the control loop (Adafruit's driver busy-waits forever).
"""

from __future__ import annotations

import errno

from edge.errors import BusError
from edge.hal.clock import Clock
from edge.hal.i2c import I2CBus, I2CMessage, transfer_bits

FULL_SCALE_V = {6.144: 0, 4.096: 1, 2.048: 2, 1.024: 3, 0.512: 4, 0.256: 5}
DATA_RATES = {
    "ADS1115": (8, 16, 32, 64, 128, 250, 475, 860),
    "ADS1015": (128, 250, 490, 920, 1600, 2400, 3300),
}
CONVERSION, CONFIG = 0x00, 0x01
COMPARATOR_OFF = 0x0003


class ADS1x15:
    """One ADS1115 or ADS1015 on an I2C bus.

    Args:
        bus: the I2C port.
        clock: the clock port (waits and deadlines).
        address: 7-bit address (0x48..0x4B).
        variant: ``ADS1115`` (16 bit, up to 860 SPS) or ``ADS1015`` (12 bit, up to 3300 SPS).
        full_scale_v: PGA range, one of 6.144, 4.096, 2.048, 1.024, 0.512, 0.256 [V].
        data_rate_sps: samples per second, one the chip supports.
        timeout_factor: a conversion may take this many periods before it is declared dead.
    """

    def __init__(
        self,
        bus: I2CBus,
        clock: Clock,
        *,
        address: int = 0x48,
        variant: str = "ADS1115",
        full_scale_v: float = 4.096,
        data_rate_sps: int = 860,
        timeout_factor: float = 3.0,
    ) -> None:
        if variant not in DATA_RATES:
            raise ValueError(f"ADC variant {variant!r} unknown; use ADS1115 or ADS1015")
        if full_scale_v not in FULL_SCALE_V:
            raise ValueError(f"full_scale_v {full_scale_v} not a PGA range; use one of {sorted(FULL_SCALE_V)}")
        if data_rate_sps not in DATA_RATES[variant]:
            raise ValueError(f"{variant} has no {data_rate_sps} SPS; use one of {DATA_RATES[variant]}")
        self._bus, self._clock, self.address, self.variant = bus, clock, address, variant
        self.full_scale_v = full_scale_v
        self.data_rate_sps = data_rate_sps
        self.timeout_factor = timeout_factor
        self._reply = I2CMessage.read_bytes(2)
        self._started: float | None = None

    @property
    def conversion_time_s(self) -> float:
        return 1.0 / self.data_rate_sps

    @staticmethod
    def read_bus_bits() -> int:
        """I2C clocks of one single-shot read: config write, one status poll, result read."""
        config = [I2CMessage.write([CONFIG, 0, 0])]
        register_read = [I2CMessage.write([CONFIG]), I2CMessage.read_bytes(2)]
        return transfer_bits(config) + 2 * transfer_bits(register_read)

    def _config(self, channel: int, single_shot: bool) -> int:
        if not 0 <= channel <= 3:
            raise ValueError(f"ADC channel {channel} outside 0..3")
        return (
            (0x8000 if single_shot else 0)
            | ((4 + channel) << 12)
            | (FULL_SCALE_V[self.full_scale_v] << 9)
            | (0x0100 if single_shot else 0)
            | (DATA_RATES[self.variant].index(self.data_rate_sps) << 5)
            | COMPARATOR_OFF
        )

    def _write(self, register: int, value: int) -> None:
        self._bus.transfer(self.address, [I2CMessage.write([register, value >> 8, value & 0xFF])])

    def _read(self, register: int) -> int:
        self._bus.transfer(self.address, [I2CMessage.write([register]), self._reply])
        return (self._reply.data[0] << 8) | self._reply.data[1]

    def volts(self, code: int) -> float:
        """Register code -> volts at the configured range (two's complement)."""
        signed = code - 0x10000 if code & 0x8000 else code
        return signed / 32768.0 * self.full_scale_v

    def read_volts(self, channel: int) -> float:
        """One single-shot conversion of ``channel`` against GND [V], with a deadline."""
        self.start_single(channel)
        self._clock.sleep_until(self._clock.now() + self.conversion_time_s)
        return self.finish_volts()

    def start_single(self, channel: int) -> None:
        """Start a single-shot conversion of ``channel``; :meth:`finish_volts` collects it."""
        self._write(CONFIG, self._config(channel, single_shot=True))
        self._started = self._clock.now()

    def finish_volts(self) -> float:
        """The conversion :meth:`start_single` began [V]: no wait if it is done (pipelined
        use), else poll the OS bit until ``timeout_factor`` periods after the start."""
        started = self._started
        if started is None:
            raise RuntimeError("finish_volts() without start_single()")
        deadline = started + self.timeout_factor * self.conversion_time_s
        self._started = None
        while not self._read(CONFIG) & 0x8000:
            now = self._clock.now()
            if now >= deadline:
                raise BusError(
                    errno.ETIMEDOUT,
                    f"ADC 0x{self.address:02x}: conversion not done after {now - started:.4f} s "
                    f"({self.timeout_factor:g} periods); check the chip and its supply",
                )
            self._clock.sleep_until(min(deadline, now + self.conversion_time_s / 4))
        return self.volts(self._read(CONVERSION))

    def start_continuous(self, channel: int) -> None:
        """Convert ``channel`` continuously at the data rate; read with :meth:`latest_volts`."""
        self._write(CONFIG, self._config(channel, single_shot=False))

    def latest_volts(self) -> float:
        """The most recent continuous conversion [V]."""
        return self.volts(self._read(CONVERSION))
