"""Noise on a parameter vector, common random numbers, and a probability with its interval.

A chaotic outcome is reported as a probability: the share of ``n`` noisy copies of a
parameter vector that give it, with a 95 % **Wilson score interval** (:func:`wilson`):
``(p + z^2/2n +- z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)``, z = 1.96, which stays inside
[0, 1] and is not empty at 0 or n successes.

**Noise**: :func:`normal_draws` gives the (n, D) standard-normal draws of a seed (one row per
copy, one column per coordinate, in that fixed order), and :func:`perturb` adds them, times
each coordinate's standard deviation, to a vector and clips into limits. **Common random
numbers**: two vectors perturbed with the draws of the same seed meet the same noise, so the
difference of their probabilities is measured on paired copies (only the copies whose
outcome differs count), not as two independent estimates.

Compute only: no files, no printing, no MuJoCo.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.errors import InputError

__all__ = ["Z95", "wilson", "Probability", "normal_draws", "perturb", "counts"]

#: Wilson interval's z for 95 %.
Z95 = 1.959963984540054


def wilson(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval for ``k`` successes in ``n`` trials (95 % by default).

    Args:
        k: successes, 0 <= k <= n.
        n: trials, > 0.
        z: the normal quantile (1.96: 95 %).

    Returns:
        (lo, hi).

    Raises:
        InputError: k or n out of range.
    """
    if n <= 0 or not 0 <= k <= n:
        raise InputError(f"wilson: need 0 <= k <= n and n > 0, got k={k}, n={n}")
    p = k / n
    den = 1 + z * z / n
    mid = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    # at k = 0 (k = n) the lower (upper) end is exactly 0 (1); rounding must not move it inside
    return (0.0 if k == 0 else max(0.0, mid - half)), (1.0 if k == n else min(1.0, mid + half))


@dataclass(frozen=True)
class Probability:
    """``k`` of ``n`` trials gave the outcome: ``p`` = k/n and its 95 % Wilson interval.

    Args:
        k: the trials that gave it.
        n: the trials.
        p: k / n.
        lo, hi: the 95 % Wilson interval.

    Returns:
        The estimate (frozen).
    """

    k: int
    n: int
    p: float
    lo: float
    hi: float

    @classmethod
    def of(cls, k: int, n: int) -> Probability:
        lo, hi = wilson(k, n)
        return cls(k=int(k), n=int(n), p=k / n, lo=lo, hi=hi)

    def text(self) -> str:
        return f"{100 * self.p:.0f} % ({self.k}/{self.n}; 95 % CI {100 * self.lo:.0f}-{100 * self.hi:.0f} %)"


def normal_draws(seed: int, n: int, dim: int) -> np.ndarray:
    """Standard-normal draws of ``seed``: row i perturbs copy i (common random numbers).

    Args:
        seed: the seed.
        n: copies.
        dim: coordinates.

    Returns:
        (n, dim) float64 array.
    """
    return np.random.default_rng(seed).standard_normal((n, dim))


def perturb(base, sigma, draws, lo, hi) -> np.ndarray:
    """Copies of ``base``: ``clip(base + sigma * draws[i], lo, hi)`` per coordinate.

    Args:
        base: (D,) float64 array.
        sigma: (D,) float64 array, or a float: the noise's standard deviations.
        draws: (n, D) standard-normal draws (:func:`normal_draws`).
        lo, hi: (D,) limits.

    Returns:
        (n, D) float64 array.
    """
    return np.clip(np.asarray(base, dtype=float) + np.asarray(sigma, dtype=float) * np.asarray(draws, dtype=float),
                   np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))


def counts(labels) -> dict:
    """{label: count} of outcome labels, the most frequent first (ties in first-seen order)."""
    got: dict = {}
    for x in labels:
        got[x] = got.get(x, 0) + 1
    return dict(sorted(got.items(), key=lambda kv: -kv[1]))
