#!/usr/bin/env python3
"""Writes tests/data/exp_cases.txt, and with --table prints the constants
and the 2^(j/128) table of src/interval/exp.rs, from Python's decimal
module (correctly rounded at the precision set below).

    python3 tests/data/exp_cases.py > tests/data/exp_cases.txt
    python3 tests/data/exp_cases.py --table
"""
from decimal import Decimal as D, getcontext
import math
import random
import struct
import sys

getcontext().prec = 80
LN2 = D(2).ln()
N = 128


def bits(f):
    return struct.unpack('<Q', struct.pack('<d', f))[0]


def table():
    c = LN2 / N
    m, e = math.frexp(float(c))
    hi = math.ldexp(math.floor(m * 2**36), e - 36)  # 36 significant bits
    print(f"INV_LN2_N = {float(N / LN2)!r}")
    print(f"LN2_N_HI = {hi!r}")
    print(f"LN2_N_LO = {float(c - D(hi))!r}")
    for j in range(N):
        v = (LN2 * j / N).exp()
        h = float(v)
        print(f"    ({h!r}, {float(v - D(h))!r}),")


def cases():
    getcontext().prec = 60
    random.seed(20261126)
    xs = []
    xs += [random.uniform(-700, 700) for _ in range(1000)]
    xs += [random.uniform(-5, 5) for _ in range(800)]
    xs += [random.uniform(-20, 0) for _ in range(400)]
    xs += [random.uniform(-0.01, 0.01) for _ in range(300)]
    # Halfway between reduction points, and either side of them.
    for _ in range(300):
        k = random.randint(-129000, 129000)
        x = float((D(k) + D('0.5')) * LN2 / N)
        xs += [x, math.nextafter(x, math.inf), math.nextafter(x, -math.inf)]
    xs += [random.uniform(699, 700) for _ in range(50)]
    xs += [random.uniform(-700, -699) for _ in range(50)]
    xs += [0.0, -0.0, 1.0, -1.0, 700.0, -700.0, 1e-300, -1e-300, 5e-324,
           1e-17, -1e-17, 0.5, 2.0**-30]
    xs += [float(i) for i in range(-700, 701, 7)]
    print('# x, the f64 nearest exp(x), and the side of it the real value lies on')
    print('# (-1 below, 0 equal, 1 above), as f64 bits in hex; from 60-digit')
    print('# decimal arithmetic (Python decimal), for src/interval/exp.rs.')
    for x in xs:
        v = D(x).exp()
        cr = float(v)
        d = v - D(cr)
        side = (d > 0) - (d < 0)
        print(f'{bits(x):016x} {bits(cr):016x} {side}')


if __name__ == '__main__':
    table() if '--table' in sys.argv else cases()
