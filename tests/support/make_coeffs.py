#!/usr/bin/env python3
"""A random coefficients.json (spec schema) for the database tests.

make_coeffs.py SERIAL SEED [SIGMA_GYRO_BIAS] > file: biases and M drawn from SEED, σ fixed
(gyro bias σ as given, default 1e-6 rad/s), an extra model term that the store must keep verbatim.
"""
import json
import random
import sys

serial, seed = sys.argv[1], int(sys.argv[2])
sgb = float(sys.argv[3]) if len(sys.argv) > 3 else 1e-6
r = random.Random(seed)


def tri(bias, sb):
    return {"bias": [r.gauss(0, bias) for _ in range(3)],
            "M": [[r.gauss(0, 3e-3 if i == j else 3e-4) for j in range(3)] for i in range(3)],
            "sigma_bias": [sb] * 3, "sigma_M": [[2e-5] * 3 for _ in range(3)]}


print(json.dumps({"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": serial},
                  "gyro": tri(1e-3, sgb), "accel": tri(0.1, 1e-4), "temperature": {"model": "linear", "k": [1, 2, 3]}}))
