#!/usr/bin/env python3
"""Writes tests/data/tight_cases.txt: sums, products, quotients and square
roots of f64s with their bounds rounded down and up, from exact rational
arithmetic (Python's fractions), for the oracle of tests/common/tight.rs.

    python3 tests/data/tight_cases.py > tests/data/tight_cases.txt
"""
from fractions import Fraction as F
import math
import random
import struct

# Round to nearest overflows from MAX plus half its ulp on.
OVERFLOW = F(2**1024 - 2**970)


def bits(f):
    return struct.unpack('<Q', struct.pack('<d', f))[0]


def nearest(x):
    """x rounded to nearest, ties to even (int / int is correctly rounded)."""
    if abs(x) >= OVERFLOW:
        return math.inf if x > 0 else -math.inf
    return x.numerator / x.denominator


def bounds(x, r):
    """[RD(x), RU(x)] from x and its rounded-to-nearest value r."""
    if r == math.inf:
        return math.nextafter(r, 0), r
    if r == -math.inf:
        return r, math.nextafter(r, 0)
    if F(r) == x:
        return r, r
    if F(r) < x:
        return r, math.nextafter(r, math.inf)
    return math.nextafter(r, -math.inf), r


def exact(op, a, b):
    a, b = F(a), F(b)
    return {'add': a + b, 'mul': a * b, 'div': a / b}[op]


def sqrt_bounds(a):
    r = math.sqrt(a)  # correctly rounded (IEEE 754)
    sq = F(r) ** 2
    if sq == F(a):
        return r, r
    if sq < F(a):
        return r, math.nextafter(r, math.inf)
    return math.nextafter(r, -math.inf), r


def value(rng):
    """A float of random sign, significand and exponent, often subnormal,
    tiny, huge or a small integer."""
    kind = rng.randrange(6)
    if kind == 0:
        return float(rng.randrange(-40, 41) or 1)
    if kind == 1:
        return rng.choice([-1, 1]) * rng.randrange(1, 2**52) * 2.0**-1074
    exp = {2: rng.randrange(-40, 41), 3: rng.randrange(-1074, -900),
           4: rng.randrange(900, 1023), 5: rng.randrange(-600, 600)}[kind]
    m = rng.randrange(2**52, 2**53)
    return rng.choice([-1, 1]) * math.ldexp(m, exp - 52)


def main():
    rng = random.Random(1788)
    print("# op, a, b (0 for sqrt), and the f64 bounds of the exact result")
    print("# rounded down and up, as f64 bits in hex; from exact rational")
    print("# arithmetic (Python fractions), for tests/common/tight.rs.")
    hand = [('add', 0.1, 0.2), ('add', 1e308, 1e308), ('add', -1e308, -1e308),
            ('add', 1e-310, 2e-310), ('add', 1.0, 2.0**-53), ('add', 1.0, 2.0**-60),
            ('mul', 0.1, 3.0), ('mul', 1e-200, 1e-200), ('mul', -1e-200, 1e-200),
            ('mul', 3 * 5e-324, 0.5), ('mul', 5e-324, 0.5), ('mul', 1e300, 1e10),
            ('mul', -1e300, 1e10), ('mul', 2.0**-537, 2.0**-537),
            ('div', 1.0, 3.0), ('div', 2.0, 3.0), ('div', 0.7, 0.1),
            ('div', 5e-324, 3.0), ('div', 5e-324, 2.0), ('div', 1e300, 1e-10),
            ('div', -1.0, 10.0), ('div', 6.0, 4.0)]
    cases = list(hand)
    for op in ('add', 'mul', 'div'):
        for _ in range(60):
            a, b = value(rng), value(rng)
            cases.append((op, a, b))
    for a in (2.0, 3.0, 0.1, 4.0, 1e-310, 5e-324, 2 * 5e-324, 1.7976931348623157e308):
        cases.append(('sqrt', a, 0.0))
    for _ in range(40):
        cases.append(('sqrt', abs(value(rng)), 0.0))
    for op, a, b in cases:
        if op == 'sqrt':
            lo, hi = sqrt_bounds(a)
        else:
            x = exact(op, a, b)
            lo, hi = bounds(x, nearest(x))
        print(f"{op} {bits(a):016x} {bits(b):016x} {bits(lo):016x} {bits(hi):016x}")


main()
