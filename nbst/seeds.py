"""nbst's one seed helper: every random choice in nbst starts from a seed that passes here.

A seed is an integer in ``[0, SEED_MAX]`` (numpy's ``SeedSequence`` and the kernels' int64
state take any such integer). ``None`` means "draw one": :func:`resolve_seed` draws it from
fresh entropy, in that same range, so a run without ``--seed`` can record the seed it used and
be repeated. :func:`check_random_state` is in the style of scikit-learn's: it turns ``None``, an
integer, a ``SeedSequence`` or a ``Generator`` into a ``numpy.random.Generator``.

Example::

    from nbst.seeds import resolve_seed, check_random_state

    seed = resolve_seed(None)              # 0 <= seed <= 2**63 - 1, recorded in the output
    rng = check_random_state(seed)         # the same stream for the same seed, on any machine
    rng2 = check_random_state(rng)         # a Generator passes through unchanged

This module sits in the lowest layer beside the registry (it imports numpy and the errors).
"""
from __future__ import annotations

import numbers
from typing import Union

import numpy as np

from nbst.errors import InputError

__all__ = ["SEED_MAX", "SeedLike", "check_seed", "draw_seed", "derived_seed", "resolve_seed", "check_random_state"]

#: The largest seed nbst takes: numpy's SeedSequence and the kernels' int64 state take any seed
#: from 0 up to this. Every drawn seed lies in the same range.
SEED_MAX = 2**63 - 1

SeedLike = Union[None, int, np.integer, np.random.SeedSequence, np.random.Generator]


def check_seed(seed: object, *, what: str = "seed") -> int:
    """The seed as a Python int, refused unless it is an integer in ``[0, SEED_MAX]``.

    Args:
        seed: the seed given (an ``int`` or numpy integer; ``bool`` is refused).
        what: how the message names it (``"--seed"``, ``"seed of the crash file"``).

    Returns:
        ``int(seed)``.

    Raises:
        InputError: ``seed`` is not an integer, or lies outside ``[0, SEED_MAX]``.
    """
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise InputError(f"{what} must be an integer in [0, 2^63-1], not {seed!r}")
    s = int(seed)
    if not 0 <= s <= SEED_MAX:
        raise InputError(f"{what} must be an integer in [0, 2^63-1], not {s}")
    return s


def draw_seed() -> int:
    """A fresh seed from the operating system's entropy, in ``[0, SEED_MAX]``.

    Returns:
        the seed, to be recorded with whatever it drives so the run can be repeated.
    """
    return int(np.random.SeedSequence().generate_state(1, np.uint64)[0] & np.uint64(SEED_MAX))


def derived_seed(seed: int, *salt: int) -> int:
    """A seed in [0, 2^63) derived from ``seed`` and ``salt``: one stream per stage of a search
    (numpy's ``SeedSequence([seed, *salt])``), the same for the same ``seed`` and ``salt``."""
    return int(np.random.SeedSequence([int(seed), *salt]).generate_state(1, np.uint64)[0] >> 1)


def resolve_seed(seed: object = None, *, what: str = "seed") -> int:
    """The seed a run uses: the one given (checked), or a fresh one when ``seed`` is None.

    Args:
        seed: ``None`` to draw one, else an integer in ``[0, SEED_MAX]``.
        what: how a refusal names it.

    Returns:
        an int in ``[0, SEED_MAX]``.

    Raises:
        InputError: ``seed`` is given but is not an integer in range.
    """
    return draw_seed() if seed is None else check_seed(seed, what=what)


def check_random_state(seed: SeedLike = None, *, what: str = "seed") -> np.random.Generator:
    """A ``numpy.random.Generator`` from whatever stands for a seed (after scikit-learn).

    Args:
        seed: ``None`` (fresh entropy), an integer in ``[0, SEED_MAX]``, a
            ``numpy.random.SeedSequence``, or a ``numpy.random.Generator`` (returned as is).
        what: how a refusal names it.

    Returns:
        the generator; an integer seed gives ``np.random.default_rng(seed)``, the same stream on
        every machine.

    Raises:
        InputError: ``seed`` is none of the above, or an integer out of range.
    """
    if isinstance(seed, np.random.Generator):
        return seed
    if isinstance(seed, np.random.SeedSequence):
        return np.random.default_rng(seed)
    return np.random.default_rng(resolve_seed(seed, what=what))
