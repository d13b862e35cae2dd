"""The arithmetic of the controller builds, to the last bit (reference §11).

Two float modes exist (:class:`~pymotoros.models.FloatMode`):

``X87_EXTENDED`` (DX100, DX200, YRC1000, YRC1000micro)
    Every C statement is evaluated in the x87 80-bit format (64-bit mantissa) and
    rounded to float32 only when stored in a float variable. ``numpy.longdouble`` is
    that format on x86-64 Linux, so each operation below is one longdouble operation
    and each store is an ``astype(float32)``. Conversions to int truncate straight
    from the register: the exact product of two float32 values (48 significant bits)
    fits a float64, so those are done in float64 without any rounding.

``STRICT_SINGLE`` (FS100)
    Every operation is rounded to float32 (numpy float32 arithmetic), so a product is
    rounded *before* it is truncated to an int.

The scalar rules both the client and the controller need (:func:`f32`, :func:`c_int`,
:func:`pulse`, :func:`from_pulse`) live in :mod:`pymotoros.models.rules`, numpy-free,
and are re-exported here; this module adds their array forms and the interpolation.

The operand order of each expression is the order the specification writes it; in
extended precision it decides the last bit only in rare cases, in single precision
more often, so it is kept everywhere. The functions here are the only place that
knows about float modes; everything else calls them.

Longdouble arithmetic is slow in numpy, so the x87 coefficients and positions are
first computed in float64 and kept only where they provably round to the same float32
as the x87 would (:func:`positions_x87_checked`); the rest goes through longdouble.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from pymotoros.models import FloatMode
from pymotoros.models.rules import c_int as c_int
from pymotoros.models.rules import f32 as f32
from pymotoros.models.rules import from_pulse as from_pulse
from pymotoros.models.rules import pulse as pulse
from pymotoros.motion.constants import INT32_MAX, INT32_MIN

F32Array = npt.NDArray[np.float32]
I64Array = npt.NDArray[np.int64]
F64Array = npt.NDArray[np.float64]
AnyArray = npt.NDArray[Any]

LD: Final = np.longdouble
"""The x87 extended format (64-bit mantissa) on x86-64 Linux."""

if np.finfo(LD).nmant != 63:  # pragma: no cover - only on platforms we do not support
    raise ImportError(
        "pymotoros.motion needs numpy.longdouble to be the x87 80-bit format (x86-64 Linux); "
        f"here it has a {np.finfo(LD).nmant + 1}-bit mantissa"
    )

_INT32_LOW: Final = float(INT32_MIN) - 1.0
_INT32_HIGH: Final = float(INT32_MAX) + 1.0


def f32_tuple(values: Sequence[float], size: int) -> tuple[float, ...]:
    """``values`` rounded to float32 and zero-filled to ``size`` entries."""
    padded = list(values) + [0.0] * (size - len(values))
    try:
        return struct.unpack(f"<{size}f", struct.pack(f"<{size}f", *padded))
    except OverflowError:
        return tuple(f32(v) for v in padded)


def c_int_array(values: npt.NDArray[np.float64], mode: FloatMode) -> I64Array:
    """:func:`c_int` over an array (float64 input holding exact values)."""
    if np.abs(values).max(initial=0.0) < _INT32_HIGH - 1.0:  # NaN fails this test too
        return values.astype(np.int64)
    ok = (values > _INT32_LOW) & (values < _INT32_HIGH)
    out = np.where(ok, values, 0.0).astype(np.int64)
    bad = ~ok
    if mode is FloatMode.X87_EXTENDED:
        out[bad] = INT32_MIN
    else:
        out[bad & (values > 0)] = INT32_MAX
        out[bad & (values < 0)] = INT32_MIN
    return out


def seconds_to_ms(seconds: float, mode: FloatMode) -> int:
    """A point time in integer ms: ``(int)(time * 1000)`` on the float32 time (§3.4, §11).

    x87: truncated from the exact product (0.7 s → 699 ms); FS100: from the product
    rounded to float32 (0.7 s → 700 ms).
    """
    return float32_seconds_to_ms(f32(seconds), mode)


def float32_seconds_to_ms(t: float, mode: FloatMode) -> int:
    """:func:`seconds_to_ms` of a time already rounded to float32."""
    # The float64 product of 24 × 10 significant bits is exact; FS100 rounds it once.
    product = t * 1000.0 if mode is FloatMode.X87_EXTENDED else f32(t * 1000.0)
    return c_int(product, mode)


def pulses(values: F32Array, factors: F32Array, mode: FloatMode) -> I64Array:
    """:func:`pulse` over arrays (``factors`` broadcasts over the last axis)."""
    if mode is FloatMode.X87_EXTENDED:
        product = values.astype(np.float64) * factors.astype(np.float64)
    else:
        with np.errstate(over="ignore", invalid="ignore"):
            product = (values * factors).astype(np.float64)
    return c_int_array(product, mode)


def ms_to_seconds(ms: AnyArray) -> F32Array:
    """``(int ms) / 1000.0`` stored as float32: T and τ of §5.4 (§11).

    The same on both builds: an x87 quotient rounded to 64 bits, an FS100 quotient
    rounded to 24 bits and a float64 one rounded to 53 bits all round to the same
    float32, because k/1000 is never within 2⁻³⁵ (relative) of a float32 midpoint.
    """
    out: F32Array = (ms / 1000.0).astype(np.float32)
    return out


_COEF_CONSTANTS: dict[tuple[type, int], tuple[AnyArray, ...]] = {}


def _constants(dtype: type, ndim: int) -> tuple[AnyArray, ...]:
    """[6, −12], [2, 1], [2, 6] and [−1, 1] shaped to broadcast over (2, …, n)."""
    key = (dtype, ndim)
    found = _COEF_CONSTANTS.get(key)
    if found is None:
        shape = (2,) + (1,) * ndim
        found = tuple(
            np.array(pair, dtype=dtype).reshape(shape)
            for pair in ((6, -12), (2, 1), (2, 6), (-1, 1))
        )
        _COEF_CONSTANTS[key] = found
    return found


def coefficients_kernel(
    rows: AnyArray, den_a: AnyArray, den_b: AnyArray, mode: FloatMode
) -> F32Array:
    """a1 and a2 of the specification, stacked (2, …, n) and stored as float32 (§5.4).

    ``rows`` is (4, …, n): x0, v0, x1, v1 (longdouble for x87, float32 for FS100);
    ``den_a`` is (2, …, 1): T·T and (T·T)·T; ``den_b`` is (2, …, 1): T and T·T.
    Both coefficients are computed at once, term by term as the specification writes
    them: a1 = (6·Δ)/(T·T) − (2·(v1 + 2·v0))/T and
    a2 = (−12·Δ)/((T·T)·T) + (6·(v1 + v0))/(T·T), with Δ = x1 − x0. Subtracting is
    adding the exact negation, and 1·v0 is exact, so each element sees exactly the
    operations of its own formula.
    """
    c_delta, c_v0, c_sum, c_sign = _constants(rows.dtype.type, rows.ndim - 1)
    delta = rows[2] - rows[0]
    first = (delta * c_delta) / den_a
    second = ((rows[3] + c_v0 * rows[1]) * c_sum) / den_b
    out: F32Array = (first + second * c_sign).astype(np.float32)
    return out


_SIGNIFICAND_SCALE: Final = float(1 << 53)
"""frexp's mantissa (in [0.5, 1)) × 2⁵³ is the float64's 53-bit significand as an integer."""
_LOW29: Final = (1 << 29) - 1
_MID29: Final = 1 << 28
RISK_FACTOR: Final = 33.0
"""Safety factor of :func:`positions_x87_checked` (2⁵ from the error analysis, plus slack)."""

COEF_RISK_FACTOR: Final = 12.0
"""Safety factor of the coefficient checks. Each coefficient is two terms and a sum;
on its longest path (a2: Δ, 12·Δ, T·T·T, the quotient; v1 + v0, 6·(…), the quotient;
the sum) a value sees five roundings, each off by at most 2⁻⁵³ (float64) or 2⁻⁶⁴ (x87)
of a quantity no larger than the sum of the magnitudes of the two terms. So float64
and x87 differ by less than 5.001 × 2⁻⁵³ × that sum; 12 leaves more than a factor 2.
(``tests/motion/test_extended_precision.py`` measures the difference.) On dense, smooth
trajectories the two terms nearly cancel, so this factor decides how many segments are
redone in longdouble."""


def coefficients_x87_scalar(
    x0: Sequence[float], v0: Sequence[float], x1: Sequence[float], v1: Sequence[float], t: float
) -> list[float] | None:
    """a1 (n values) then a2 (n values) as the x87 stores them, or None if unsure.

    Evaluated in float64 and checked as in :func:`positions_x87_checked`: each formula
    has at most five roundings, so the float64 and x87 values differ by less than
    2⁻⁴⁸ × the sum of the magnitudes of the two terms; when that is closer to a float32
    midpoint than the float64 value is, None tells the caller to use the longdouble
    kernel. A tick-by-tick simulation computes a segment per point; this avoids a dozen
    numpy calls each time.
    """
    tt = t * t  # exact: 48 significant bits
    ttt = tt * t
    values: list[float] = []
    sizes: list[float] = []
    for p0, s0, p1, s1 in zip(x0, v0, x1, v1, strict=True):
        d = p1 - p0
        first = (6 * d) / tt
        second = (2 * (s1 + 2 * s0)) / t
        values.append(first - second)
        sizes.append(abs(first) + abs(second))
    for p0, s0, p1, s1 in zip(x0, v0, x1, v1, strict=True):
        d = p1 - p0
        third = (-12 * d) / ttt
        fourth = (6 * (s1 + s0)) / tt
        values.append(third + fourth)
        sizes.append(abs(third) + abs(fourth))
    frexp = math.frexp
    scale = _SIGNIFICAND_SCALE
    for value, size in zip(values, sizes, strict=True):
        if size == 0.0:
            continue
        if not abs(value) < 1e30:  # first: NaN and infinities have no significand bits
            return None
        low = int(frexp(value)[0] * scale) & _LOW29  # the 29 bits past float32
        distance = min(abs(low - _MID29), 1 << 27)
        if not distance * abs(value) > COEF_RISK_FACTOR * size:
            return None
    return list(f32_tuple(values, len(values)))


def coefficients_x87_exact(
    x0: Sequence[float], v0: Sequence[float], x1: Sequence[float], v1: Sequence[float], t: float
) -> list[float]:
    """What :func:`coefficients_x87_scalar` returns, always: computed in longdouble."""
    rows = np.array([*x0, *v0, *x1, *v1], dtype=LD).reshape(4, len(x0))
    et = LD(t)
    tt = et * et
    den_a = np.array([[tt], [tt * et]], dtype=LD)
    den_b = np.array([[et], [tt]], dtype=LD)
    out: list[float] = (
        coefficients_kernel(rows, den_a, den_b, FloatMode.X87_EXTENDED).ravel().tolist()
    )
    return out


def positions_x87_scalar(
    x0: Sequence[float],
    v0: Sequence[float],
    h1: Sequence[float],
    a2: Sequence[float],
    taus: Sequence[float],
    t: float,
) -> list[tuple[float, ...]] | None:
    """:func:`positions_x87_checked` in plain Python floats, or None if unsure.

    For a segment with few steps (points as dense as the period) a dozen numpy calls
    cost more than the arithmetic: this evaluates the same float64 expressions (Python
    floats are float64) with the same check against :func:`position_bound` (``t`` is
    the segment length), one row of float32 values per τ. None: some value is too close
    to a float32 midpoint or too large, and the caller uses the longdouble path.
    """
    tt = t * t
    ttt = tt * t
    bounds = [
        (abs(p) + abs(s) * t + abs(h) * tt + abs(c) * ttt / 6) * RISK_FACTOR - 1e-300
        for p, s, h, c in zip(x0, v0, h1, a2, strict=True)
    ]
    frexp = math.frexp
    scale = _SIGNIFICAND_SCALE
    out: list[tuple[float, ...]] = []
    for tau in taus:
        tau2 = tau * tau
        row: list[float] = []
        for p, s, h, c, bound in zip(x0, v0, h1, a2, bounds, strict=True):
            f = p + s * tau
            f += h * tau2
            f += ((c * tau2) * tau) / 6
            size = abs(f)
            low = int(frexp(size)[0] * scale) & _LOW29
            if not (min(abs(low - _MID29), 1 << 27) * size > bound and size < 1e30):
                return None
            row.append(f)
        out.append(f32_tuple(row, len(row)))
    return out


_SINGLES: dict[int, struct.Struct] = {}
_ROUNDING_SLACK: Final = 2.0**-52
"""Relative bound (twice the float64 unit roundoff) on the rounding of ``value ± e``."""
_COEF_ALLOWANCE: Final = COEF_RISK_FACTOR * 2.0**-53
_POSITION_ALLOWANCE: Final = RISK_FACTOR * 2.0**-53


def _singles(count: int) -> struct.Struct:
    """``count`` little-endian float32: packing rounds each double to nearest, even."""
    found = _SINGLES.get(count)
    if found is None:
        found = _SINGLES[count] = struct.Struct(f"<{count}f")
    return found


def coefficients_x87_interval(
    x0: Sequence[float], v0: Sequence[float], x1: Sequence[float], v1: Sequence[float], t: float
) -> tuple[float, ...] | None:
    """a1 (n values) then a2 (n values) as the x87 stores them, or None if unsure: the
    coefficient half of :func:`small_segment_x87` (see there for the interval argument),
    which its callers share. Cheaper than :func:`coefficients_x87_scalar` (one
    ``struct`` round trip instead of a bit test per value), and the same values
    whenever both answer.
    """
    n = len(x0)
    tt = t * t  # exact: 48 significant bits
    ttt = tt * t
    low1: list[float] = []
    high1: list[float] = []
    low2: list[float] = []
    high2: list[float] = []
    allowance = _COEF_ALLOWANCE
    slack = _ROUNDING_SLACK
    for p0, s0, p1, s1 in zip(x0, v0, x1, v1, strict=True):
        d = p1 - p0
        first = (6 * d) / tt
        second = (2 * (s1 + 2 * s0)) / t
        a = first - second
        e = (abs(first) + abs(second)) * allowance + abs(a) * slack
        low1.append(a - e)
        high1.append(a + e)
        third = (-12 * d) / ttt
        fourth = (6 * (s1 + s0)) / tt
        a = third + fourth
        e = (abs(third) + abs(fourth)) * allowance + abs(a) * slack
        low2.append(a - e)
        high2.append(a + e)
    ends = _singles(4 * n)
    try:
        rounded = ends.unpack(ends.pack(*low1, *low2, *high1, *high2))
    except OverflowError:  # beyond float32
        return None
    coef = rounded[: 2 * n]
    if coef != rounded[2 * n :]:  # NaN never equals itself, so it lands here too
        return None
    return coef


def small_segment_x87(
    x0: Sequence[float],
    v0: Sequence[float],
    x1: Sequence[float],
    v1: Sequence[float],
    t: float,
    taus: Sequence[float],
) -> list[tuple[float, ...]] | None:
    """The float32 positions at ``taus`` of a segment of length ``t`` on the x87, or None.

    :func:`coefficients_x87_scalar` then :func:`positions_x87_scalar` fused into one
    pass, for the segment of one or two steps that a tick computes when points come as
    often as the period: the same float64 expressions, operand for operand, and the
    same error allowances, but checked as an interval. Each float64 value F is within
    ``e`` of the x87's value X (``e``: ``COEF_RISK_FACTOR`` × 2⁻⁵³ × the magnitudes of
    a coefficient's two terms, or ``RISK_FACTOR`` × 2⁻⁵³ × :func:`position_bound`'s sum
    for a position; both at least twice the proven bounds), so X lies in [F − e, F + e];
    ``|F|`` × 2⁻⁵² more covers the rounding of the two ends. Rounding to float32 is
    monotonic, so when both ends round to the same float32, X does too, and so does F
    (where both ends round to zero, from either side, the sign of that zero may differ
    from the x87's; no pulse, a truncated product, can see it).
    All ends are rounded in one ``struct`` call and compared as two tuples, which costs
    far less than a per-value bit test. None (some value straddles a float32 midpoint,
    overflows float32, or is not a number): the caller takes the longer path, with
    longdouble where needed. A float result is the x87's in every case, which is what
    keeps the paths bit-identical.
    """
    coef = coefficients_x87_interval(x0, v0, x1, v1, t)
    if coef is None:
        return None
    n = len(x0)
    tt = t * t
    ttt = tt * t
    slack = _ROUNDING_SLACK
    a1, a2 = coef[:n], coef[n:]
    allowance = _POSITION_ALLOWANCE
    ttt6 = ttt / 6
    row_ends = _singles(2 * n)
    out: list[tuple[float, ...]] = []
    for tau in taus:
        tau2 = tau * tau
        low: list[float] = []
        high: list[float] = []
        for p, s, a, c in zip(x0, v0, a1, a2, strict=True):
            h = a / 2  # exact
            f = p + s * tau
            f += h * tau2
            f += ((c * tau2) * tau) / 6
            e = (abs(p) + abs(s) * t + abs(h) * tt + abs(c) * ttt6) * allowance + abs(f) * slack
            low.append(f - e)
            high.append(f + e)
        try:
            both = row_ends.unpack(row_ends.pack(*low, *high))
        except OverflowError:
            return None
        row = both[:n]
        if row != both[n:]:
            return None
        out.append(row)
    return out


SCALAR_REDO: Final = 8
"""Up to this many risky coefficients are redone one by one with longdouble scalars."""


def _coefficient_x87(k: int, x0: float, v0: float, x1: float, v1: float, t: float) -> float:
    """One coefficient (k = 0: a1, 1: a2) as :func:`coefficients_kernel` computes it in
    longdouble, operation for operation, stored as float32."""
    e0, f0, e1, f1, et = LD(x0), LD(v0), LD(x1), LD(v1), LD(t)
    tt = et * et
    if k == 0:
        value = ((e1 - e0) * 6) / tt + (((f1 + 2 * f0) * 2) / et) * -1
    else:
        value = ((e1 - e0) * -12) / (tt * et) + ((f1 + 1 * f0) * 6) / tt
    return float(np.float32(value))


def coefficients_x87_checked(rows: F64Array, t: F64Array) -> F32Array:
    """:func:`coefficients_kernel` for the x87, computed in float64 and checked.

    ``rows`` (4, S, n): x0, v0, x1, v1 as float64 holding float32 values; ``t`` (S, 1):
    the float32 segment lengths. Same argument as :func:`coefficients_x87_scalar`; the
    segments with a value too close to a float32 midpoint are redone in longdouble.
    """
    tt = t * t  # exact
    den_a = np.array((tt, tt * t))
    den_b = np.array((t, tt))
    c_delta, c_v0, c_sum, c_sign = _constants(np.float64, rows.ndim - 1)
    first = ((rows[2] - rows[0]) * c_delta) / den_a
    second = ((rows[3] + c_v0 * rows[1]) * (c_sum * c_sign)) / den_b
    value = first + second
    size = np.abs(first) + np.abs(second)
    dist = np.minimum(np.abs((value.view(np.int64) & _LOW29) - _MID29), 1 << 27)
    magnitude = np.abs(value)
    risky = (dist * magnitude <= COEF_RISK_FACTOR * size) & (size > 0)
    if not magnitude.max(initial=0.0) < 1e30:  # also NaN
        risky |= ~(magnitude < 1e30)
    out: F32Array = value.astype(np.float32)
    if risky.any():
        where = np.nonzero(risky)
        if len(where[0]) <= SCALAR_REDO:
            # A few values: longdouble scalars cost less than a dozen array operations.
            for index in zip(*(w.tolist() for w in where), strict=True):
                k, rest = index[0], index[1:]
                x0, v0, x1, v1 = (float(rows[(i, *rest)]) for i in range(4))
                out[index] = _coefficient_x87(k, x0, v0, x1, v1, float(t[(*rest[:-1], 0)]))
            return out
        # Redo the segments (rows) concerned in longdouble.
        redo = risky.reshape(2, -1, risky.shape[-1]).any(axis=(0, 2)).reshape(risky.shape[1:-1])
        et = t[redo].astype(LD)
        ett = et * et
        out[:, redo] = coefficients_kernel(
            rows[:, redo].astype(LD),
            np.stack((ett, ett * et)),
            np.stack((et, ett)),
            FloatMode.X87_EXTENDED,
        )
    return out


def positions_x87(
    x0: AnyArray, v0: AnyArray, h1: AnyArray, a2: AnyArray, lt: AnyArray, lt2: AnyArray
) -> F32Array:
    """((x0 + v0·τ) + (a1·τ·τ)/2) + (a2·τ·τ·τ)/6 on the x87, stored as float32 (§11).

    All arguments longdouble; ``h1`` = a1/2, ``lt`` = τ and ``lt2`` = τ·τ, shaped
    (K, 1) against (n,) coefficients or (N, 1) against (N, n) rows. a1·τ and τ·τ are
    exact (48 bits), so (a1·τ·τ)/2 is one rounding of a1·τ²/2, computed as
    (a1/2)·(τ·τ); a2·τ·τ·τ keeps its two roundings as (a2·(τ·τ))·τ.
    """
    s = x0 + v0 * lt
    s += h1 * lt2
    s += ((a2 * lt2) * lt) / 6
    out: F32Array = s.astype(np.float32)
    return out


def position_bound(
    x0: F64Array, v0: F64Array, h1: F64Array, a2: F64Array, t: float | F64Array
) -> F64Array:
    """RISK_FACTOR × (|x0| + |v0|·T + |a1/2|·T² + |a2|·T³/6): bounds the terms of every
    position of a segment of length T. Slightly below 0 where all are 0: such a
    position is exactly 0 and needs no check."""
    tt = t * t
    m = np.abs(x0) + np.abs(v0) * t + np.abs(h1) * tt + np.abs(a2) * (tt * t) / 6
    out: F64Array = m * RISK_FACTOR - 1e-300
    return out


def positions_x87_checked(
    x0: F64Array, v0: F64Array, h1: F64Array, a2: F64Array, tau: F64Array, bound: F64Array
) -> F32Array:
    """:func:`positions_x87`, computed in float64 and checked, as float32.

    All inputs hold float32 values; ``h1`` = a1/2, ``tau`` is (K, 1) or (N, 1), ``bound``
    comes from :func:`position_bound`. The float64 result F and the x87 result X differ
    by less than 2⁻⁴⁸·M, M the sum of the magnitudes of the terms (at most six roundings
    of 2⁻⁵³ + 2⁻⁶⁴ each). float32 rounding only changes at the midpoint between two
    float32 values, where the 29 bits float64 has beyond float32 read 1000…0; when F is
    farther than that bound from it, float32(F) = float32(X). The rare elements that
    are not are recomputed in longdouble, exactly as the x87 does.
    """
    tau2 = tau * tau  # exact: 48 bits
    f = x0 + v0 * tau
    f += h1 * tau2
    f += ((a2 * tau2) * tau) / 6
    out = f.astype(np.float32)
    dist = np.minimum(np.abs((f.view(np.int64) & _LOW29) - _MID29), 1 << 27)
    size = np.abs(f)
    risky = dist * size <= bound
    if not size.max(initial=0.0) < 1e30:  # also NaN
        risky |= ~(size < 1e30)
    if risky.any():
        where = np.nonzero(risky)
        shape = risky.shape
        lt = np.broadcast_to(tau, shape)[where].astype(LD)
        out[where] = positions_x87(
            np.broadcast_to(x0, shape)[where].astype(LD),
            np.broadcast_to(v0, shape)[where].astype(LD),
            np.broadcast_to(h1, shape)[where].astype(LD),
            np.broadcast_to(a2, shape)[where].astype(LD),
            lt,
            lt * lt,
        )
    return out


def positions_single(
    x0: F32Array, v0: F32Array, a1: F32Array, a2: F32Array, tau: F32Array
) -> F32Array:
    """The same position on the FS100: every operation rounded to float32."""
    p = x0 + v0 * tau
    p = p + ((a1 * tau) * tau) / 2
    p = p + (((a2 * tau) * tau) * tau) / 6
    return p.astype(np.float32)


def positions(
    x0: F32Array, v0: F32Array, a1: F32Array, a2: F32Array, tau: F32Array, mode: FloatMode
) -> F32Array:
    """The interpolated positions for float32 inputs (``tau`` shaped (K, 1))."""
    with np.errstate(all="ignore"):
        if mode is FloatMode.X87_EXTENDED:
            f0, g0 = x0.astype(np.float64), v0.astype(np.float64)
            h1, c2 = a1.astype(np.float64) / 2, a2.astype(np.float64)
            t = tau.astype(np.float64)
            bound = position_bound(f0, g0, h1, c2, float(t.max(initial=0.0)))
            return positions_x87_checked(f0, g0, h1, c2, t, bound)
        return positions_single(x0, v0, a1, a2, tau)


def velocities(
    v0: F32Array, a1: F32Array, a2: F32Array, tau: F32Array, mode: FloatMode
) -> F32Array:
    """(v0 + a1·τ) + (a2·τ·τ)/2, stored as float32 (the interpolated velocity, §5.4)."""
    with np.errstate(all="ignore"):
        if mode is FloatMode.X87_EXTENDED:
            lt = tau.astype(LD)
            s = v0.astype(LD) + a1.astype(LD) * lt
            s += ((a2.astype(LD) * lt) * lt) / 2
            return s.astype(np.float32)
        p = v0 + a1 * tau
        p = p + ((a2 * tau) * tau) / 2
        return p.astype(np.float32)
