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

The operand order of each expression is the order the specification writes it; in
extended precision it decides the last bit only in rare cases, in single precision
more often, so it is kept everywhere. The functions here are the only place that
knows about float modes; everything else calls them.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
import numpy.typing as npt

from pymotoros.models import FloatMode
from pymotoros.motion.constants import INT32_MAX, INT32_MIN

F32Array = npt.NDArray[np.float32]
I64Array = npt.NDArray[np.int64]
AnyArray = npt.NDArray[np.generic]

LD: Final = np.longdouble
"""The x87 extended format (64-bit mantissa) on x86-64 Linux."""

if np.finfo(LD).nmant != 63:  # pragma: no cover - only on platforms we do not support
    raise ImportError(
        "pymotoros.motion needs numpy.longdouble to be the x87 80-bit format (x86-64 Linux); "
        f"here it has a {np.finfo(LD).nmant + 1}-bit mantissa"
    )

_F32_1000: Final = np.float32(1000.0)
_LD_1000: Final = LD(1000)
_INT32_LOW: Final = float(INT32_MIN) - 1.0
_INT32_HIGH: Final = float(INT32_MAX) + 1.0


def f32(value: float) -> float:
    """``value`` rounded to float32 (as a Python float). Overflow gives ±inf, as on the wire."""
    with np.errstate(over="ignore"):
        return float(np.float32(value))


def c_int(value: float, mode: FloatMode) -> int:
    """C's ``(int)value``: truncation toward zero.

    Out of the int32 range (or NaN) C leaves the result undefined; the x87 store gives
    the "integer indefinite" value INT32_MIN, the PowerPC conversion saturates (NaN
    gives 0). That is what the two builds' instructions do, not something the
    reference states; it only matters for absurd inputs.
    """
    if _INT32_LOW < value < _INT32_HIGH:
        return int(value)
    if mode is FloatMode.X87_EXTENDED or math.isnan(value):
        return INT32_MIN if mode is FloatMode.X87_EXTENDED else 0
    return INT32_MAX if value > 0 else INT32_MIN


def c_int_array(values: npt.NDArray[np.float64], mode: FloatMode) -> I64Array:
    """:func:`c_int` over an array (float64 input holding exact values)."""
    ok = (values > _INT32_LOW) & (values < _INT32_HIGH)
    if ok.all():
        return values.astype(np.int64)
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
    t = f32(seconds)
    # The float64 product of 24 × 10 significant bits is exact; FS100 rounds it once.
    product = t * 1000.0 if mode is FloatMode.X87_EXTENDED else f32(t * 1000.0)
    return c_int(product, mode)


def pulse(value: float, factor: float, mode: FloatMode) -> int:
    """``(int)(value * factor)`` for one float32 value and float32 pulse ratio (§5.7, §11)."""
    product = value * factor  # exact: two float32 operands
    if mode is FloatMode.STRICT_SINGLE:
        product = f32(product)
    return c_int(product, mode)


def pulses(values: F32Array, factors: F32Array, mode: FloatMode) -> I64Array:
    """:func:`pulse` over arrays (``factors`` broadcasts over the last axis)."""
    if mode is FloatMode.X87_EXTENDED:
        product = values.astype(np.float64) * factors.astype(np.float64)
    else:
        with np.errstate(over="ignore", invalid="ignore"):
            product = (values * factors).astype(np.float64)
    return c_int_array(product, mode)


def from_pulse(count: int, factor: float, mode: FloatMode) -> float:
    """ConvertToRosPos: ``pulse / factor`` stored as float32 (§5.7)."""
    if mode is FloatMode.X87_EXTENDED:
        return float(np.float32(LD(count) / LD(factor)))
    return float(np.float32(count) / np.float32(factor))


def ms_to_seconds(ms: AnyArray, mode: FloatMode) -> F32Array:
    """``(int ms) / 1000.0`` stored as float32: T and τ of §5.4 (§11)."""
    if mode is FloatMode.X87_EXTENDED:
        return (ms.astype(LD) / _LD_1000).astype(np.float32)
    return ms.astype(np.float32) / _F32_1000


def coefficients(
    x0: F32Array, v0: F32Array, x1: F32Array, v1: F32Array, t: F32Array, mode: FloatMode
) -> tuple[F32Array, F32Array]:
    """The specification's a1 and a2 for a segment of length ``t`` s (t > 0), as float32.

    a1 = 6·Δ/T² − 2·(v1 + 2·v0)/T and a2 = −12·Δ/T³ + 6·(v1 + v0)/T², one statement
    each. Arrays broadcast; ``t`` has shape (..., 1) for per-segment rows.
    """
    with np.errstate(all="ignore"):
        if mode is FloatMode.X87_EXTENDED:
            ex0, ev0, ex1, ev1, et = (a.astype(LD) for a in (x0, v0, x1, v1, t))
            d = ex1 - ex0
            tt = et * et
            a1 = (6 * d) / tt - (2 * (ev1 + 2 * ev0)) / et
            a2 = (-12 * d) / (tt * et) + (6 * (ev1 + ev0)) / tt
            return a1.astype(np.float32), a2.astype(np.float32)
        d32 = x1 - x0
        tt32 = t * t
        b1 = (6 * d32) / tt32 - (2 * (v1 + 2 * v0)) / t
        b2 = (-12 * d32) / (tt32 * t) + (6 * (v1 + v0)) / tt32
        return b1.astype(np.float32), b2.astype(np.float32)


def positions(
    x0: F32Array, v0: F32Array, a1: F32Array, a2: F32Array, tau: F32Array, mode: FloatMode
) -> F32Array:
    """((x0 + v0·τ) + (a1·τ·τ)/2) + (a2·τ·τ·τ)/6, stored as float32 (§5.4, §11).

    ``tau`` has shape (K, 1) against (n,) coefficients, or (N, 1) against (N, n) rows.
    In extended precision a1·τ and τ·τ are exact (48 bits), so (a1·τ)·τ/2 is the single
    rounding of a1·τ²/2 and is computed as (a1/2)·(τ·τ); a2·τ·τ·τ keeps its two
    roundings, ((a2·τ²)·τ).
    """
    with np.errstate(all="ignore"):
        if mode is FloatMode.X87_EXTENDED:
            lt = tau.astype(LD)
            lt2 = lt * lt
            s = x0.astype(LD) + v0.astype(LD) * lt
            s += (a1.astype(LD) * 0.5) * lt2
            s += ((a2.astype(LD) * lt2) * lt) / 6
            return s.astype(np.float32)
        p = x0 + v0 * tau
        p = p + ((a1 * tau) * tau) / 2
        p = p + (((a2 * tau) * tau) * tau) / 6
        return p.astype(np.float32)


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
