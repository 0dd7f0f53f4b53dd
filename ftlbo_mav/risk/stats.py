"""What many flights say together: probabilities with exact confidence intervals, the
spread of each figure. Pure."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


def _binom_cdf(k: int, n: int, p: float) -> float:
    """P(X <= k) for X ~ Binomial(n, p), summed in log space (exact for any n here)."""
    if p <= 0.0:
        return 1.0
    if p >= 1.0:
        return 1.0 if k >= n else 0.0
    i = np.arange(0, k + 1)
    logs = (math.lgamma(n + 1) - np.array([math.lgamma(j + 1) + math.lgamma(n - j + 1)
                                           for j in i])
            + i * math.log(p) + (n - i) * math.log1p(-p))
    top = logs.max()
    return float(min(1.0, math.exp(top) * np.exp(logs - top).sum()))


def _solve(f, target: float) -> float:
    """The p in [0, 1] where the decreasing ``f(p)`` meets ``target`` (bisection)."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if f(mid) > target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def clopper_pearson(events: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """The exact (Clopper-Pearson) interval of a probability seen ``events`` times in
    ``n`` flights. With no event the upper bound is what ``n`` flights can show:
    ``1 - (alpha/2) ** (1/n)`` (about 3.7/n at 95 %)."""
    if not 0 <= events <= n or n < 1:
        raise ValueError(f"events must be within 0..n and n >= 1, got {events} of {n}")
    half = (1.0 - confidence) / 2.0
    # P(X >= events | lower) = alpha/2 and P(X <= events | upper) = alpha/2
    lower = 0.0 if events == 0 else _solve(lambda p: _binom_cdf(events - 1, n, p), 1.0 - half)
    upper = 1.0 if events == n else _solve(lambda p: _binom_cdf(events, n, p), half)
    return lower, upper


@dataclass(frozen=True)
class Probability:
    """``events`` of ``flights``, the estimate and its 95 % interval."""

    what: str
    events: int
    flights: int
    low: float
    high: float

    @property
    def estimate(self) -> float:
        return self.events / self.flights

    def describe(self) -> str:
        return (f"{self.what}: {self.events} of {self.flights} flights "
                f"({self.estimate:.1%}; 95 % interval {self.low:.2%}-{self.high:.2%})")

    def document(self) -> dict:
        return {"what": self.what, "events": self.events, "flights": self.flights,
                "estimate": self.estimate, "ci95": [self.low, self.high]}


def probability(what: str, hits: Sequence[bool]) -> Probability:
    n, k = len(hits), int(sum(bool(h) for h in hits))
    low, high = clopper_pearson(k, n)
    return Probability(what, k, n, low, high)


def spread(values: Sequence[float | None]) -> dict:
    """Min, 5th, 50th, 95th percentile, max and mean of the finite values; ``n`` of them."""
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)], float)
    if len(v) == 0:
        return {"n": 0}
    q = np.percentile(v, [5, 50, 95])
    return {"n": int(len(v)), "min": float(v.min()), "p5": float(q[0]),
            "median": float(q[1]), "p95": float(q[2]), "max": float(v.max()),
            "mean": float(v.mean())}


def ecdf(values: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """The empirical CDF: sorted values and the fraction at or below each."""
    v = np.sort(np.asarray([x for x in values if x is not None and math.isfinite(x)], float))
    return v, np.arange(1, len(v) + 1) / max(len(v), 1)
