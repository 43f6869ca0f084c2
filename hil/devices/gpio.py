"""Emulated GPIO lines implementing :class:`edge.hal.gpio.GpioLines`."""

from __future__ import annotations

import errno
from collections.abc import Callable

from edge.errors import BusError


class EmulatedGpio:
    """Named lines: ``outputs`` are driven by the edge, the rest are inputs the rig drives."""

    def __init__(self, lines: dict[str, bool], outputs: set[str]) -> None:
        self._values = dict(lines)
        self._outputs = set(outputs)
        self.before_access: list[Callable[[], None]] = []  # the rig's fault schedule
        self.error: int | None = None  # fault: every access raises OSError(error)

    def fail(self, code: int | None) -> None:
        """From now on every access raises a plain ``OSError(code)``, as libgpiod does when the
        chip goes away (None: healthy again)."""
        self.error = code

    def _check(self, name: str) -> None:
        for hook in self.before_access:
            hook()
        if self.error is not None:
            raise OSError(self.error, f"gpiochip: line {name!r}: {errno.errorcode.get(self.error, self.error)}")

    def get(self, name: str) -> bool:
        self._check(name)
        if name not in self._values:
            raise BusError(errno.ENOENT, f"GPIO line {name!r} not configured; lines: {sorted(self._values)}")
        return self._values[name]

    def set(self, name: str, value: bool) -> None:
        self._check(name)
        if name not in self._outputs:
            raise BusError(errno.EPERM, f"GPIO line {name!r} is not an output")
        self._values[name] = bool(value)

    def level(self, name: str) -> bool:
        """The rig side: what a line is at, whatever faults the edge's access meets."""
        return self._values[name]

    def drive_input(self, name: str, value: bool) -> None:
        """The rig side: set an input line (e.g. press the e-stop)."""
        if name in self._outputs or name not in self._values:
            raise ValueError(f"{name!r} is not an input line")
        self._values[name] = bool(value)

    def close(self) -> None:
        """Nothing to release."""
