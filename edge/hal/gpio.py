"""The GPIO port: named lines, ``get(name)`` and ``set(name, value)``.

Line names are the rig's (``valve_enable`` output, ``estop`` input); which chip offset they are
is configuration. The Linux backend uses libgpiod v2 (``gpiod.request_lines``).
"""

from __future__ import annotations

import errno
from collections.abc import Mapping
from typing import Protocol

from edge.errors import BusError


class GpioLines(Protocol):
    """What the runtime needs of its GPIO lines."""

    def get(self, name: str) -> bool:
        """Logical value of a line (active = True)."""

    def set(self, name: str, value: bool) -> None:
        """Drive an output line."""

    def close(self) -> None:
        """Release the lines (outputs return to the kernel's default)."""


class GpiodLines:
    """libgpiod v2 backend.

    Args:
        chip_path: ``/dev/gpiochipN``.
        outputs: line name -> offset, requested as outputs driven inactive.
        inputs: line name -> offset, requested as inputs.
        active_low: names whose electrical level is inverted.
    """

    def __init__(
        self,
        chip_path: str,
        outputs: Mapping[str, int],
        inputs: Mapping[str, int],
        active_low: frozenset[str] = frozenset(),
    ) -> None:
        import gpiod
        from gpiod.line import Direction, Value

        self._value = Value
        self._offsets = {**outputs, **inputs}
        config = {
            offset: gpiod.LineSettings(
                direction=Direction.OUTPUT, active_low=name in active_low, output_value=Value.INACTIVE
            )
            for name, offset in outputs.items()
        }
        config.update(
            {
                offset: gpiod.LineSettings(direction=Direction.INPUT, active_low=name in active_low)
                for name, offset in inputs.items()
            }
        )
        try:
            self._request = gpiod.request_lines(chip_path, config=config, consumer="pmactl")  # type: ignore[arg-type]
        except OSError as exc:
            raise BusError(exc.errno, f"cannot request GPIO lines on {chip_path}: {exc}") from exc

    def get(self, name: str) -> bool:
        try:
            return self._request.get_value(self._offsets[name]) == self._value.ACTIVE
        except OSError as exc:  # libgpiod reports a vanished chip or a released request as OSError
            raise BusError(exc.errno or errno.EIO, f"GPIO line {name!r}: read failed ({exc})") from exc

    def set(self, name: str, value: bool) -> None:
        try:
            self._request.set_value(self._offsets[name], self._value.ACTIVE if value else self._value.INACTIVE)
        except OSError as exc:
            raise BusError(exc.errno or errno.EIO, f"GPIO line {name!r}: write failed ({exc})") from exc

    def close(self) -> None:
        try:
            self._request.release()
        except OSError:  # already gone (chip removed): nothing left to release
            pass
