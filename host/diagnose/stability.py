"""Does the verdict hold on less of the same record? (``pmactl diagnose --stability``)

A verdict near its thresholds changes when a little of the record is left out: on the tuning
and fresh plants (``bench/diagnose_stability.py``) cutting the first 7 or 14 s of a 100 s record
changed about half of the verdicts in v6, and 27-31 % since v7's calibrated floor. So the
diagnosis is repeated without the last :data:`END_SHARES` of the record (the end, not the start:
cutting the start can move the first sample where the hysteresis memory is known and so drop
much more than the cut) and the verdict is reported as holding or as borderline. What that is
worth, from the end cuts of 100 s records: with v6's rules a cause that changed was right about
half the time (tuning 6/12, fresh 8/15, blind2 2/6), one that held 11/14 on the tuning plants
but only 10/18 and 15/28 on the fresh and second blind plants, whose wrong verdicts are stable
ones; with v7's on the third blind plants, 3/6 and 3/5. So "borderline" is a warning, "holds"
is no proof. The verdict itself is not changed. A verdict whose evidence sits in one stretch near the
end (a payload hung on once) is borderline too, however large its gain: it rests on one event.
Costs one diagnosis per share.
"""

from __future__ import annotations

from edge.errors import DataError
from host.data import Measurement
from host.diagnose.run import Diagnosis, decimated_with_warning, diagnose

END_SHARES = (0.1, 0.2)


def diagnose_with_stability(m: Measurement, *, folds: int = 4, progress: bool | None = None) -> Diagnosis:
    """:func:`host.diagnose.run.diagnose` of ``m``, repeated without the last 10 % and 20 % of
    it; ``confidence["stability"]`` holds each shortened record's verdict and ``holds``: False
    when one differs, None when none differs but one could not be diagnosed, else True; the
    reason says which.

    A long record is decimated once, before it is cut, so that all three diagnoses run at one
    sampling rate (decimating each on its own would compare a half-rate whole record with
    full-rate cuts just above the limit)."""
    m, notes = decimated_with_warning(m)
    whole = diagnose(m, folds=folds, progress=progress)
    whole.notes[:0] = notes
    shortened: dict[str, object] = {}
    refusals: list[str] = []
    for share in END_SHARES:
        kept = len(m) - int(round(share * len(m)))
        key = f"without_last_{share:.0%}"
        try:
            # a cut is judged from the same known memory as the whole record, never from an
            # assumed state the whole record did not need
            cut = diagnose(m.slice(0, kept), folds=folds, progress=progress, assume_state=whole.memory_assumed)
            shortened[key] = cut.cause
        except DataError as refusal:  # too short for these folds once shortened: not evidence either way
            shortened[key] = "not checked"
            refusals.append(f"without the last {share:.0%}: {refusal}")
    checked = [cause for cause in shortened.values() if cause != "not checked"]
    holds: bool | None = False if any(cause != whole.cause for cause in checked) else (None if refusals else True)
    whole.confidence["stability"] = {**shortened, "holds": holds}
    shares = " and ".join(f"{share:.0%}" for share in END_SHARES)
    if holds is None:
        whole.reason += f"; the stability could not be checked ({'; '.join(refusals)})"
    elif holds:
        whole.reason += f"; the verdict holds without the last {shares} of the record"
    else:
        others = ", ".join(f"{key.replace('_', ' ')}: {cause}" for key, cause in shortened.items())
        whole.reason += (
            f"; borderline: the verdict changes when the end of the record is left out ({others}); "
            "treat it as a hint and record longer or repeat the run"
        )
    return whole
