#!/usr/bin/env python3
"""Compares the field files (field_<k>.csv) of two runs: prints the largest difference,
relative to the largest magnitude of the column's quantity in the first run (the heat flux's
columns qx, qy, qz share one), and exits 1 when it is above the tolerance, when the files
differ in shape or when a difference is not a number.

Usage: python3 scripts/fields-differ.py RUN_A RUN_B TOLERANCE
"""
import csv
import glob
import math
import os
import sys


def quantity(name):
    return "q" if name.startswith("q") else name


def main(a, b, tolerance):
    worst, where = 0.0, ""
    files = sorted(glob.glob(os.path.join(a, "field_*.csv")))
    if not files:
        sys.exit(f"{a}: no field files")
    for f in files:
        x = list(csv.reader(open(f)))
        y = list(csv.reader(open(os.path.join(b, os.path.basename(f)))))
        if len(x) != len(y) or any(len(p) != len(q) for p, q in zip(x, y)):
            sys.exit(f"{os.path.basename(f)}: the files differ in shape")
        head, x, y = x[0], x[1:], y[1:]
        largest = {}
        for c, name in enumerate(head):
            m = max((abs(float(r[c])) for r in x), default=0.0)
            largest[quantity(name)] = max(largest.get(quantity(name), 0.0), m)
        for c, name in enumerate(head):
            scale = largest[quantity(name)] or 1.0
            for p, q in zip(x, y):
                d = abs(float(p[c]) - float(q[c])) / scale
                if math.isnan(d):
                    sys.exit(f"{os.path.basename(f)} {name}: not a number")
                if d > worst:
                    worst, where = d, f"{os.path.basename(f)} {name}"
    print(f"largest relative difference {worst:.2e} ({where or 'none'})")
    if not worst <= tolerance:
        sys.exit(1)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], float(sys.argv[3]))
