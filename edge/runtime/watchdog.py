"""The watchdog: vents the valve from its own thread when the loop stops ticking."""

from __future__ import annotations

import threading
import time

from edge.runtime.rig import Rig


class Watchdog:
    """Vents the valve from its own thread if the loop stops ticking for ``timeout_s``.

    The loop may be stalled inside a bus transfer; :meth:`Rig.vent` drops the GPIO enable line
    first, which does not share that bus.
    """

    def __init__(self, rig: Rig, timeout_s: float) -> None:
        self._rig, self.timeout_s = rig, timeout_s
        self.heartbeat = time.monotonic()
        self.fired_after_s: float | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="pmactl-watchdog", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.timeout_s / 4):
            stalled = time.monotonic() - self.heartbeat
            if stalled > self.timeout_s and self.fired_after_s is None:
                self.fired_after_s = stalled
                self._rig.vent()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()
