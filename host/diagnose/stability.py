"""Does the verdict hold on less of the same record? (``pmactl diagnose --stability``)

A verdict near its thresholds changes when a little of the record is left out: on the tuning
and fresh plants (``bench/diagnose_stability.py``) cutting the first 7 or 14 s of a 100 s record
changed about half of the verdicts, and a cause named on the whole record was right far more
often when it held over the cuts than when it did not. So the diagnosis is repeated without the
last :data:`END_SHARES` of the record (the end, not the start: cutting the start can move the
first sample where the hysteresis memory is known and so drop much more than the cut) and the
verdict is reported as holding or as borderline. The verdict itself is not changed: a borderline
one is still the best single answer, now with its doubt stated. A verdict whose evidence sits in
one stretch near the end (a payload hung on once) is borderline too, however large its gain: it
rests on one event. Costs one diagnosis per share.
"""

from __future__ import annotations

from edge.errors import DataError
from host.data import Measurement
from host.diagnose.run import Diagnosis, diagnose

END_SHARES = (0.1, 0.2)


def diagnose_with_stability(m: Measurement, *, folds: int = 4, progress: bool | None = None) -> Diagnosis:
    """:func:`host.diagnose.run.diagnose` of ``m``, repeated without the last 10 % and 20 % of
    it; ``confidence["stability"]`` holds each shortened record's verdict and whether all agree,
    and the reason says so."""
    whole = diagnose(m, folds=folds, progress=progress)
    shortened: dict[str, str] = {}
    for share in END_SHARES:
        kept = len(m) - int(round(share * len(m)))
        try:
            cause = diagnose(m.slice(0, kept), folds=folds, progress=progress).cause
        except DataError:  # too short to diagnose once shortened: the verdict cannot be checked
            cause = "refused"
        shortened[f"without_last_{share:.0%}"] = cause
    holds = all(cause == whole.cause for cause in shortened.values())
    whole.confidence["stability"] = {**shortened, "holds": holds}
    shares = " and ".join(f"{share:.0%}" for share in END_SHARES)
    if holds:
        whole.reason += f"; the verdict holds without the last {shares} of the record"
    else:
        others = ", ".join(f"{key.replace('_', ' ')}: {cause}" for key, cause in shortened.items())
        whole.reason += (
            f"; borderline: the verdict changes when the end of the record is left out ({others}); "
            "treat it as a hint and record longer or repeat the run"
        )
    return whole
