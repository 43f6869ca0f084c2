"""The verdict: which candidate the held-out evidence names, with how much confidence, or ``none`` and why.

Per candidate and fold the gain is ``1 - RMSE_ext / RMSE_base`` on the fold's in-range held-out
rows. A candidate passes when

* its fit held: a fold where it costs more than :data:`BLOWUP_RATIO` times the baseline's error
  (or gives no finite prediction) is a failed fit, not evidence; such folds are left out, and a
  candidate that fails on more than one fold is out;
* its mean gain clears a threshold set by the folds themselves: ``max(GAIN_FLOOR, T_CRIT * sd /
  sqrt(k))``, the spread of its fold gains over ``k`` folds (a gain the folds do not agree on is
  not evidence), and it helps on at least half of the folds;
* it lowers the error by more than the noise floor allows to be chance: a mean RMSE reduction of
  at least :data:`NOISE_SHARE` times the measurement noise (at the noise floor, relative gains
  of a few percent are what any flexible term finds);
* an observed cause (load, temperature) also beats ``slow_drift``, the same flexibility in time
  alone, fold by fold by the same threshold: a slowly wandering column soaks up any drift.

Among the candidates that pass the highest mean gain wins. :func:`with_signatures` then applies
the two-stage rule: a residual signature (:mod:`host.diagnose.signatures`) at p <=
:data:`SIGNATURE_ALPHA` nominates its cause and the held-out folds confirm it (:func:`unconfirmed`),
and a held-out verdict whose own signature the record shows at p > :data:`VETO_P` is withdrawn.

The constants were calibrated on the effect-free records of the tuning plants (tests/plants,
``bench/diagnose_scorecard.py --set tuning``); the false-alarm rate they give on records never
tuned on is in the README.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from host.diagnose.candidates import CAUSES, OBSERVED_CAUSES
from host.diagnose.signatures import Signature

GAIN_FLOOR = 0.03
T_CRIT = 1.5
NOISE_SHARE = 0.25
BLOWUP_RATIO = 4.0
# rate dependence and a dead time both explain a lag; see choose() for how a near tie is read
RIVAL_MARGIN = 0.05


@dataclass
class CandidateScore:
    """One candidate's held-out record over the folds."""

    cause: str
    gains: list[float] = field(default_factory=list)  # valid folds only
    reductions: list[float] = field(default_factory=list)  # RMSE reduction [units of y], valid folds
    all_gains: list[float] = field(default_factory=list)  # every fold, failed ones included (nan: no rows)
    failed_folds: int = 0
    available: bool = True

    def add(self, base_rmse: float, ext_rmse: float | None) -> None:
        if ext_rmse is None:  # the data cannot show this term (column missing)
            self.available = False
            self.all_gains.append(0.0)
            return
        if not np.isfinite(ext_rmse) or ext_rmse > BLOWUP_RATIO * base_rmse:
            self.failed_folds += 1
            self.all_gains.append(1.0 - ext_rmse / base_rmse if np.isfinite(ext_rmse) else -np.inf)
            return
        gain = 1.0 - ext_rmse / base_rmse
        self.gains.append(gain)
        self.reductions.append(base_rmse - ext_rmse)
        self.all_gains.append(gain)

    @property
    def mean(self) -> float:
        return float(np.mean(self.gains)) if self.gains and self.available else 0.0

    @property
    def threshold(self) -> float:
        k = len(self.gains)
        spread = float(np.std(self.gains, ddof=1)) if k > 1 else np.inf
        return max(GAIN_FLOOR, T_CRIT * spread / np.sqrt(k)) if k > 1 else np.inf

    @property
    def failed(self) -> bool:
        return self.failed_folds > 1


@dataclass
class Verdict:
    cause: str
    reason: str
    decided_by: str
    confidence: dict[str, object]
    passing: list[str]


def _folds(values: list[float]) -> str:
    return ", ".join(f"{g:+.1%}" for g in values)


def why_not(s: CandidateScore, noise: float, drift: CandidateScore | None) -> str | None:
    """None when ``s`` passes, else the reason it does not."""
    if not s.available:
        return "its column is missing or constant"
    if s.failed:
        return f"its fit blew up on {s.failed_folds} folds (a failed fit, not evidence)"
    if s.mean < s.threshold:
        return (
            f"its mean gain {s.mean:+.1%} is below the {s.threshold:.1%} its fold spread requires "
            f"(fold gains {_folds(s.gains)})"
        )
    if sum(g > 0 for g in s.gains) < len(s.gains) / 2:
        return f"it helps on fewer than half of the folds ({_folds(s.gains)})"
    if float(np.mean(s.reductions)) < NOISE_SHARE * noise:
        return (
            f"it lowers the RMSE by {np.mean(s.reductions):.3g}, less than {NOISE_SHARE:g} x the noise "
            f"floor ({noise:.3g})"
        )
    if s.cause in OBSERVED_CAUSES and drift is not None and drift.gains:
        paired = [a - b for a, b in zip(s.all_gains, drift.all_gains) if np.isfinite(a) and np.isfinite(b)]
        if len(paired) > 1:
            needed = max(GAIN_FLOOR / 2, T_CRIT * float(np.std(paired, ddof=1)) / np.sqrt(len(paired)))
            if float(np.mean(paired)) < needed:
                return (
                    f"it explains no more than a slow drift in time of the same flexibility does "
                    f"(margin {np.mean(paired):+.1%}, {needed:.1%} needed)"
                )
    return None


def choose(scores: dict[str, CandidateScore], noise: float) -> Verdict:
    """The verdict over every candidate's fold record (see the module docstring)."""
    drift = scores.get("slow_drift")
    reasons = {c: why_not(s, noise, drift) for c, s in scores.items()}
    passing = [c for c in CAUSES if c in scores and reasons[c] is None]
    ranked = sorted((c for c in scores if scores[c].available), key=lambda c: scores[c].mean, reverse=True)
    best = max(passing, key=lambda c: scores[c].mean) if passing else (ranked[0] if ranked else CAUSES[0])
    decided_by = "held-out gain"
    lag_tie = best == "transport_delay" and "rate_dependence" in passing
    if lag_tie and scores["rate_dependence"].mean >= scores["transport_delay"].mean - RIVAL_MARGIN:
        # a dead time reproduces any lag, also a speed-dependent one over moderate speeds; a
        # speed-dependent lag cannot reproduce a dead time (its lag vanishes as the output stops)
        best = "rate_dependence"
        decided_by = (
            f"lag signature: a speed-dependent term scores within {RIVAL_MARGIN:.0%} of a dead time "
            f"({scores['rate_dependence'].mean:+.1%} vs {scores['transport_delay'].mean:+.1%}); a dead time mimics "
            "any lag but not the reverse, so the lag vanishes when the output stops"
        )
    elif best == "transport_delay" and "rate_dependence" in passing:
        decided_by = (
            f"lag signature: the lag persists when the output stops (dead time {scores['transport_delay'].mean:+.1%} "
            f"beats the speed-dependent terms {scores['rate_dependence'].mean:+.1%} by more than {RIVAL_MARGIN:.0%})"
        )
    elif best in OBSERVED_CAUSES and best in passing:
        decided_by = (
            f"residual vs the measured column: beats a slow drift in time of the same flexibility "
            f"({scores[best].mean:+.1%} vs {scores['slow_drift'].mean:+.1%})"
            if "slow_drift" in scores
            else "residual vs the measured column"
        )
    s = scores[best]
    others = [c for c in ranked if c != best]
    runner = others[0] if others else "none"
    confidence: dict[str, object] = {
        "over_threshold": float(s.mean - s.threshold) if np.isfinite(s.threshold) else float("-inf"),
        "over_runner_up": float(s.mean - (scores[runner].mean if others else 0.0)),
        "runner_up": runner,
        "threshold": float(s.threshold) if np.isfinite(s.threshold) else None,
        "noise_floor": noise,
    }
    if best in passing:
        reason = (
            f"{best} lowers held-out RMSE by {s.mean:.1%} on average (threshold from its fold spread "
            f"{s.threshold:.1%}; fold gains {_folds(s.gains)}"
        )
        if s.failed_folds:
            reason += f"; {s.failed_folds} failed fold left out"
        reason += f"; runner-up {runner} {scores[runner].mean:+.1%})" if others else ")"
        return Verdict(best, reason, decided_by, confidence, passing)
    why = reasons[best] or "it does not pass"
    reason = f"no extension improves held-out error convincingly: the best ({best}) does not count because {why}"
    return Verdict("none", reason, "no candidate passed", confidence, passing)


# two-stage rule: a signature at this level nominates its cause (its false-alarm rate is the
# surrogate p-value's); the held-out gain must then confirm it
SIGNATURE_ALPHA = 0.01
# a verdict of the held-out gain alone is withdrawn when its own signature, where the record can
# show one, is this far from significant: the gain then came from a term that fits structural error
VETO_P = 0.2


def unconfirmed(s: CandidateScore, noise: float) -> str | None:
    """None when the held-out folds confirm a nominated cause: the fit held, the mean gain is at
    least :data:`GAIN_FLOOR`, it helps on at least half of the folds and beats the noise floor."""
    if not s.available:
        return "its column is missing or constant"
    if s.failed:
        return f"its fit blew up on {s.failed_folds} folds"
    if s.mean < GAIN_FLOOR:
        return f"its mean held-out gain {s.mean:+.1%} is below {GAIN_FLOOR:.0%} (fold gains {_folds(s.gains)})"
    if sum(g > 0 for g in s.gains) < len(s.gains) / 2:
        return f"it helps on fewer than half of the folds ({_folds(s.gains)})"
    if float(np.mean(s.reductions)) < NOISE_SHARE * noise:
        return f"it lowers the RMSE by less than {NOISE_SHARE:g} x the noise floor ({noise:.3g})"
    return None


def with_signatures(
    verdict: Verdict, scores: dict[str, CandidateScore], signatures: dict[str, Signature], noise: float
) -> Verdict:
    """The two-stage rule over the held-out verdict: signatures nominate, held-out gains confirm,
    and a held-out verdict its own signature contradicts is withdrawn."""
    nominated = {c: g for c, g in signatures.items() if g.p_value <= SIGNATURE_ALPHA and c in scores}
    confirmed = [c for c in nominated if unconfirmed(scores[c], noise) is None]
    confidence = dict(verdict.confidence)
    confidence["signature_p"] = {c: g.p_value for c, g in signatures.items()}
    if confirmed:
        best = max(confirmed, key=lambda c: scores[c].mean)
        s, sig = scores[best], signatures[best]
        reason = (
            f"{best}: its signature is significant ({sig.detail}) and the held-out gain confirms it "
            f"({s.mean:+.1%}; fold gains {_folds(s.gains)})"
        )
        if verdict.cause not in ("none", best):
            reason += f"; the held-out gain alone ranked {verdict.cause} first"
        decided_by = f"signature (p = {sig.p_value:.2g}, <= {SIGNATURE_ALPHA:g}), confirmed by held-out gain"
        confidence["over_threshold"] = float(s.mean - GAIN_FLOOR)
        return Verdict(best, reason, decided_by, confidence, verdict.passing)
    cause = verdict.cause
    if cause in signatures and signatures[cause].p_value > VETO_P:
        sig = signatures[cause]
        reason = (
            f"no cause is named: the held-out gain favours {cause} ({scores[cause].mean:+.1%}) but its own "
            f"signature does not show it ({sig.detail}); a flexible term then fits the model's structural error"
        )
        unconfirmed_nominees = {c: unconfirmed(scores[c], noise) for c in nominated}
        if unconfirmed_nominees:
            reason += "; nominated by a signature but not confirmed: " + "; ".join(
                f"{c} ({why})" for c, why in unconfirmed_nominees.items()
            )
        return Verdict("none", reason, f"signature veto (p = {sig.p_value:.2g} > {VETO_P:g})", confidence, [])
    reason = verdict.reason
    for c in nominated:
        why = unconfirmed(scores[c], noise)
        reason += f"; {c} was nominated by its signature (p = {nominated[c].p_value:.2g}) but {why}"
    return Verdict(cause, reason, verdict.decided_by, confidence, verdict.passing)
