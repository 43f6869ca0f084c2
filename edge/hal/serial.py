"""The serial port: a byte stream with a deadline on every wait; Linux backend on pyserial.

pyserial opens and configures the port (raw mode, baud rate) by device path or URL
(``/dev/ttyACM0``, a pseudo-terminal, ``loop://``). Reads never block: the runtime waits for
data with :meth:`SerialLink.wait_readable` and its own deadline.
"""

from __future__ import annotations

import errno
import select
import time
from typing import Protocol

from edge.errors import BusError


class SerialLink(Protocol):
    def read_available(self) -> bytes:
        """Whatever has arrived (possibly nothing); never blocks."""

    def wait_readable(self, timeout_s: float) -> bool:
        """Block until data is there or ``timeout_s`` passed; True if data is there."""

    def write(self, data: bytes) -> None:
        """Send ``data``; raises :class:`BusError` if the port cannot take it."""

    def close(self) -> None: ...


class PySerialLink:
    """pyserial backend.

    Args:
        port: device path or pyserial URL.
        baud: baud rate (ignored by pseudo-terminals and USB CDC devices).
        write_timeout_s: longest a write may block before it is a bus error.
    """

    def __init__(self, port: str, baud: int = 921_600, write_timeout_s: float = 0.002) -> None:
        import serial

        try:
            # non-blocking writes, timed here: pyserial's own write timeout selects for
            # writability after a complete write and reports a timeout for data already sent
            # when the process was preempted for longer than the timeout (a loaded machine)
            self._serial = serial.serial_for_url(port, baudrate=baud, timeout=0, write_timeout=0)
        except (serial.SerialException, ValueError) as exc:
            raise BusError(
                errno.ENODEV, f"cannot open serial port {port}: {exc}; check the path and permissions"
            ) from exc
        self.port = port
        self.write_timeout_s = write_timeout_s
        try:
            self._fd: int | None = self._serial.fileno()
        except Exception:  # URL backends such as loop:// have no descriptor
            self._fd = None

    def read_available(self) -> bytes:
        try:
            waiting = self._serial.in_waiting
            return self._serial.read(waiting) if waiting else b""
        except OSError as exc:
            raise BusError(exc.errno or errno.EIO, f"serial port {self.port}: read failed ({exc})") from exc

    def wait_readable(self, timeout_s: float) -> bool:
        if self._fd is None:
            return bool(self._serial.in_waiting)
        readable, _, _ = select.select([self._fd], [], [], max(0.0, timeout_s))
        return bool(readable)

    def write(self, data: bytes) -> None:
        import serial

        view = memoryview(data)
        deadline = time.monotonic() + self.write_timeout_s
        try:
            while True:
                view = view[self._serial.write(view) or 0 :]
                if not view:
                    return
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise BusError(
                        errno.ETIMEDOUT,
                        f"serial port {self.port}: {len(view)} bytes not taken "
                        f"within {self.write_timeout_s * 1e3:g} ms",
                    )
                if self._fd is not None:
                    select.select([], [self._fd], [], remaining)
        except (serial.SerialException, OSError) as exc:
            if isinstance(exc, BusError):
                raise
            raise BusError(
                exc.errno or errno.EIO if isinstance(exc, OSError) else errno.EIO,
                f"serial port {self.port}: write failed ({exc})",
            ) from exc

    def close(self) -> None:
        self._serial.close()
