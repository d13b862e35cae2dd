"""An independent, deliberately slow model of MotoROS's interpolation for the tests.

Written from the reference text (§3.4, §5.4, §5.7, §11), not from the engine: exact
rational arithmetic with ``fractions.Fraction``, an explicit float32 rounding, and the
step loop of §5.4 run literally, one step at a time.

* x87 builds: each statement is evaluated exactly and rounded to float32 when stored.
  (The real FPU rounds each operation to a 64-bit mantissa; the two agree unless an
  exact result lies within 2⁻⁶⁴ of a float32 rounding boundary.)
* FS100: every operation is rounded to float32.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

F = Fraction


def round_f32(x: Fraction) -> Fraction:
    """Round a rational to the nearest float32, ties to even (normal range only).

    Fast path: Python rounds a Fraction to the nearest double correctly; rounding that
    double to float32 gives the same result unless the double is itself a float32
    midpoint, which is then decided exactly.
    """
    d = x.numerator / x.denominator
    m, _ = math.frexp(d)
    if (m * 2**25) % 2 == 0 or not (m * 2**25).is_integer():
        return F(struct.unpack("<f", struct.pack("<f", d))[0])
    return _round_f32_exact(x)


def _round_f32_exact(x: Fraction) -> Fraction:
    if x == 0:
        return F(0)
    sign = -1 if x < 0 else 1
    a = abs(x)
    e = math.floor(math.log2(a.numerator) - math.log2(a.denominator))
    # fix the estimate so that 2**e <= a < 2**(e+1)
    while F(2) ** e > a:
        e -= 1
    while F(2) ** (e + 1) <= a:
        e += 1
    if e > 127:
        raise OverflowError("beyond float32")
    scale = F(2) ** (e - 23)
    m = a / scale  # in [2**23, 2**24)
    q, r = divmod(m.numerator, m.denominator)
    rem = F(r, m.denominator)
    if rem > F(1, 2) or (rem == F(1, 2) and q % 2 == 1):
        q += 1
    return sign * q * scale


def f32_of(value: float) -> Fraction:
    """A Python float as the float32 the wire would carry, exactly."""
    return F(struct.unpack("<f", struct.pack("<f", value))[0])


class Arith:
    """+, ×, ÷ that round every operation (FS100) or none (x87, until the store)."""

    def __init__(self, single: bool) -> None:
        self.single = single

    def op(self, x: Fraction) -> Fraction:
        return round_f32(x) if self.single else x

    def add(self, a: Fraction, b: Fraction) -> Fraction:
        return self.op(a + b)

    def sub(self, a: Fraction, b: Fraction) -> Fraction:
        return self.op(a - b)

    def mul(self, a: Fraction, b: Fraction) -> Fraction:
        return self.op(a * b)

    def div(self, a: Fraction, b: Fraction) -> Fraction:
        return self.op(a / b)


@dataclass
class RefPoint:
    time_ms: int
    pos: list[Fraction]
    vel: list[Fraction]


@dataclass(frozen=True)
class RefAxes:
    factors: list[Fraction]
    """float32 pulses per rad, ROS order."""
    slots: list[int]
    """controller slot of each ROS axis."""
    period_ms: int
    single: bool


def to_ms(seconds: float, single: bool) -> int:
    product = f32_of(seconds) * 1000
    if single:
        product = round_f32(product)
    return int(product)  # int() of a Fraction truncates toward zero


def ref_point(time: float, pos: Sequence[float], vel: Sequence[float], axes: RefAxes) -> RefPoint:
    return RefPoint(to_ms(time, axes.single), [f32_of(p) for p in pos], [f32_of(v) for v in vel])


def to_pulses(pos: Sequence[Fraction], axes: RefAxes) -> dict[int, int]:
    out = {}
    for i, p in enumerate(pos):
        product = p * axes.factors[i]
        if axes.single:
            product = round_f32(product)
        out[axes.slots[i]] = int(product)
    return out


def interpolate(
    points: Sequence[tuple[float, Sequence[float], Sequence[float]]], axes: RefAxes
) -> list[tuple[int, list[int]]]:
    """Every queue entry (time, increments in controller slot order) for a trajectory
    whose first point is the start and where the robot stands at the start."""
    ar = Arith(axes.single)
    n = len(axes.factors)
    pts = [ref_point(t, p, v, axes) for t, p, v in points]
    current = pts[0]
    prev = to_pulses(current.pos, axes)
    leftover = 0
    period = axes.period_ms
    out: list[tuple[int, list[int]]] = []
    for end in pts[1:]:
        start = RefPoint(current.time_ms, list(current.pos), list(current.vel))
        seg_t = round_f32(ar.div(F(end.time_ms - start.time_ms), F(1000)))
        a1 = [F(0)] * n
        a2 = [F(0)] * n
        if seg_t > 0:
            for i in range(n):
                d = ar.sub(end.pos[i], start.pos[i])
                tt = ar.mul(seg_t, seg_t)
                first = ar.div(ar.mul(F(6), d), tt)
                second = ar.div(ar.mul(F(2), ar.add(end.vel[i], ar.mul(F(2), start.vel[i]))), seg_t)
                a1[i] = round_f32(ar.sub(first, second))
                third = ar.div(ar.mul(F(-12), d), ar.mul(tt, seg_t))
                fourth = ar.div(ar.mul(F(6), ar.add(end.vel[i], start.vel[i])), tt)
                a2[i] = round_f32(ar.add(third, fourth))
        calc = start.time_ms
        step = leftover if leftover else period
        while current.time_ms < end.time_ms:
            calc += step
            if calc < end.time_ms:
                tau = round_f32(ar.div(F(calc - start.time_ms), F(1000)))
                pos = []
                for i in range(n):
                    x = ar.add(start.pos[i], ar.mul(start.vel[i], tau))
                    x = ar.add(x, ar.div(ar.mul(ar.mul(a1[i], tau), tau), F(2)))
                    cubic = ar.mul(ar.mul(ar.mul(a2[i], tau), tau), tau)
                    x = ar.add(x, ar.div(cubic, F(6)))
                    pos.append(round_f32(x))
                current = RefPoint(calc, pos, list(current.vel))
                if step < period:
                    step = period
                    leftover = 0
            else:
                current = RefPoint(end.time_ms, list(end.pos), list(end.vel))
                if calc > end.time_ms:
                    leftover = calc - end.time_ms
            new = to_pulses(current.pos, axes)
            slots = sorted(new)
            out.append((current.time_ms, [new[s] - prev[s] for s in slots]))
            prev = new
    return out
