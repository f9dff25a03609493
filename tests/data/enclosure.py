#!/usr/bin/env python3
"""Writes tests/data/enclosure.txt, the reference ranges `ibeam bench
enclosure` measures enclosures against (issue 40):

    python3 tests/data/enclosure.py > tests/data/enclosure.txt

For each surface, BOXES cubes 0.01 wide placed uniformly (fixed seed) in
[-1.2, 1.2]^3, and in each the least and greatest value of f at its 8
corners and POINTS random points, evaluated with mpmath at 200 bits. The
points and every constant are f64 numbers taken exactly, and the formula
is written with the same constants for ibeam, so both evaluate the same
real function; the sampled range lies inside the true range, so every
enclosure must contain it.

Format: `surface NAME`, `formula TEXT` (ibeam syntax), then one line per
box: `X0 X1 Y0 Y1 Z0 Z1 MIN MAX`, each the shortest text of an f64 (the
range's ends rounded to nearest, which keeps them inside any enclosure
whose ends are f64).
"""
import math
import random

import mpmath

mpmath.mp.prec = 200

BOXES = 200
POINTS = 200
WIDTH = 0.01
SEED = 40

MU2 = 1.69
LAMBDA = (3 * MU2 - 1) / (3 - MU2)
SQRT2 = math.sqrt(2.0)
EXPANSION = ("x^10 - 10*x^9 + 45*x^8 - 120*x^7 + 210*x^6 - 252*x^5"
             " + 210*x^4 - 120*x^3 + 45*x^2 - 10*x + 1")

SURFACES = [
    ("kummer",
     f"(x^2 + y^2 + z^2 - {MU2!r})^2 - {LAMBDA!r}*(1 - z - {SQRT2!r}*x)"
     f"*(1 - z + {SQRT2!r}*x)*(1 + z + {SQRT2!r}*y)*(1 + z - {SQRT2!r}*y)"),
    ("klein",
     "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2)"
     " + 16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)"),
    ("power_minus_expansion", f"(x - 1)^10 - ({EXPANSION})"),
    ("expansion", EXPANSION),
]


def evaluator(formula):
    """The formula as a Python function of mpf x, y, z (exact constants:
    every literal is an f64 read exactly)."""
    text = formula.replace("^", "**")
    code = compile(text, "<formula>", "eval")

    def f(x, y, z):
        env = {"x": x, "y": y, "z": z}
        return eval(code, {"__builtins__": {}}, env)

    # Literals become mpf through the variables they meet; a literal
    # alone (1.69 - ...) is a Python float, which is exact as an f64.
    return f


def boxes(rng):
    out = []
    for _ in range(BOXES):
        lo = [-1.2 + (2.4 - WIDTH) * rng.random() for _ in range(3)]
        out.append([(a, a + WIDTH) for a in lo])
    return out


def points(rng, b):
    for k in range(8):
        yield [b[i][(k >> i) & 1] for i in range(3)]
    for _ in range(POINTS):
        yield [min(max(s[0] + (s[1] - s[0]) * rng.random(), s[0]), s[1])
               for s in b]


def main():
    rng = random.Random(SEED)
    print("# tests/data/enclosure.py: f sampled at 200 bits (mpmath) at the"
          f" corners and {POINTS} random points of {BOXES} cubes "
          f"{WIDTH} wide per surface")
    for name, formula in SURFACES:
        f = evaluator(formula)
        print(f"surface {name}")
        print(f"formula {formula}")
        for b in boxes(rng):
            vals = [f(*(mpmath.mpf(c) for c in p)) for p in points(rng, b)]
            lo, hi = min(vals), max(vals)
            sides = " ".join(f"{s[0]!r} {s[1]!r}" for s in b)
            print(f"{sides} {float(lo)!r} {float(hi)!r}")


if __name__ == "__main__":
    main()
