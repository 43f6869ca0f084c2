"""Progress of a long command on stderr: one tqdm bar over its steps, its clock kept ticking.

A step (load, fit, score, write) can take a minute on a long record without any loop to
count inside it, so the bar shows which step runs and a clock that a small thread refreshes
twice a second. The bar is on only when stderr is a terminal and the output is not ``--json``
(like ``pip``: logs and pipes get no carriage-return noise).
"""

from __future__ import annotations

import sys
import threading
from types import TracebackType
from typing import TextIO

REFRESH_S = 0.5


def wanted(json_output: bool, stream: TextIO | None = None) -> bool:
    """Show progress: not for ``--json``, and only on a terminal."""
    stream = sys.stderr if stream is None else stream
    return not json_output and hasattr(stream, "isatty") and stream.isatty()


class Steps:
    """``with Steps(4, enabled) as steps: steps.start("fitting"); ...; steps.start("scoring")``.

    Each :meth:`start` completes the previous step. Disabled, it does nothing (no import of
    tqdm, no thread).
    """

    def __init__(self, total: int, enabled: bool, description: str = "pmactl") -> None:
        self.total, self.enabled, self.description = total, enabled, description
        self._bar = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._started = 0

    def __enter__(self) -> Steps:
        if self.enabled:
            import tqdm

            tqdm.tqdm.monitor_interval = 0  # no monitor thread: the refresher below is joined on exit
            self._bar = tqdm.tqdm(
                total=self.total,
                desc=self.description,
                file=sys.stderr,
                leave=False,
                bar_format="{desc}: {n_fmt}/{total_fmt} steps [{elapsed}]",
            )
            self._thread = threading.Thread(target=self._refresh, name="pmactl-progress", daemon=True)
            self._thread.start()
        return self

    def start(self, step: str) -> None:
        """Begin ``step`` (the previous one is done)."""
        if self._bar is None:
            return
        if self._started:
            self._bar.update(1)
        self._started += 1
        self._bar.set_description_str(f"{self.description}: {step}")

    def _refresh(self) -> None:
        while not self._stop.wait(REFRESH_S):
            if self._bar is not None:
                self._bar.refresh()

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, trace: TracebackType | None
    ) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self._bar is not None:
            self._bar.close()
