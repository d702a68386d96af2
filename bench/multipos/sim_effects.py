#!/usr/bin/env python3
"""A hand-turned multi-position recording with known physics beyond calbench's 12 + 12 model, for
`calbench diagnose` on multipos recordings (issue 37 item 4; docs/diagnosis.md "Multi-position
recordings"). Written from the physics alone (no calbench code, no estimator's formula): an
ADIS16488A-class unit at latitude LAT turned through POSES static poses by smooth turns about
random axes, sampled at 200 Hz, white noise at the class's densities, a slow bias wander, the
Earth's rotation (a random heading per run), and

    measured = (I + M)·true + b + effects(true) + noise,   SI,

with the effects as their physics defines them:
    --k2 AXIS=K        accelerometer even scale term: + K·f_axis²           (K in 1/(m/s²))
    --gsens AXIS=GX,GY,GZ  gyro g-sensitivity: gyro AXIS + G·f                  (G in (rad/s)/(m/s²))

Writes IMU-TK text files (t x y z, SI) acc.txt and gyro.txt and truth.json into FOLDER.

  bench/multipos/sim_effects.py FOLDER --seed N [--k2 y=1e-5] [--gsens x=1e-4,0,0] [--poses 36] [--lat 52]
"""
import argparse
import json
import math
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hand_turn  # noqa: E402  (the turn both generators make)

ARW = 0.26 * math.pi / 180 / 60      # rad/s/√Hz  (0.26 °/√h)
VRW = 0.029 / 60                     # m/s²/√Hz   (0.029 m/s/√h)
WANDER_G = 5.1 * math.pi / 180 / 3600  # rad/s over ~300 s (bias stability 5.1 °/h)
WANDER_A = 0.1e-3 * 9.80665          # m/s² (0.1 mg)
OMEGA = 7.292115e-5
AXES = "xyz"


def matvec(A, v):
    return [sum(A[i][j] * v[j] for j in range(3)) for i in range(3)]


def matmul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(A):
    return [[A[j][i] for j in range(3)] for i in range(3)]


def unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder")
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--poses", type=int, default=36)
    ap.add_argument("--lat", type=float, default=52.0, help="site latitude, deg")
    ap.add_argument("--k2", action="append", default=[], help="AXIS=K: accelerometer K·f² (1/(m/s²))")
    ap.add_argument("--gsens", action="append", default=[], help="AXIS=GX,GY,GZ: gyro g-sensitivity ((rad/s)/(m/s²))")
    a = ap.parse_args()
    rnd = random.Random(a.seed)
    rate, g = 200.0, 9.81
    dt = 1 / rate
    k2 = [0.0, 0.0, 0.0]
    for s in a.k2:
        ax, v = s.split("=")
        k2[AXES.index(ax)] = float(v)
    G = [[0.0] * 3 for _ in range(3)]
    for s in a.gsens:
        ax, v = s.split("=")
        G[AXES.index(ax)] = [float(x) for x in v.split(",")]
    truth = {"effects": {"scale_k2_accel": k2, "g_sensitivity_gyro": G}}
    for name, bias, skew in (("gyro", 2e-3, 1e-3), ("accel", 0.05, 1e-3)):
        truth[name] = {"M": [[rnd.gauss(0, 2e-3) if i == j else rnd.gauss(0, skew) for j in range(3)] for i in range(3)],
                       "bias": [rnd.gauss(0, bias) for _ in range(3)]}
    lat = math.radians(a.lat)
    heading = rnd.uniform(0, 2 * math.pi)
    # Earth rate and gravity in a level frame (x north turned by the heading, y, z up).
    w_ie = [OMEGA * math.cos(lat) * math.cos(heading), -OMEGA * math.cos(lat) * math.sin(heading), OMEGA * math.sin(lat)]
    C = [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]  # body → level
    sg, sa = ARW * math.sqrt(rate), VRW * math.sqrt(rate)
    wander = {"gyro": [0.0] * 3, "accel": [0.0] * 3}
    phi = math.exp(-dt / 300.0)
    rows = {"gyro": [], "accel": []}
    t = 0.0

    def emit(w_body):
        nonlocal t
        CT = transpose(C)
        f = matvec(CT, [0.0, 0.0, g])             # specific force of a still unit: up
        w = [w_body[i] + x for i, x in enumerate(matvec(CT, w_ie))]
        extra = {"accel": [k2[i] * f[i] * f[i] for i in range(3)], "gyro": matvec(G, f)}
        for name, true, sig, ws in (("gyro", w, sg, WANDER_G), ("accel", f, sa, WANDER_A)):
            e = truth[name]
            wd = wander[name]
            for i in range(3):
                wd[i] = phi * wd[i] + math.sqrt(1 - phi * phi) * ws * rnd.gauss(0, 1)
            m = [sum(((1.0 if i == j else 0.0) + e["M"][i][j]) * true[j] for j in range(3)) + e["bias"][i] + extra[name][i]
                 + wd[i] + rnd.gauss(0, sig) for i in range(3)]
            rows[name].append("%.5f %.9e %.9e %.9e\n" % (t, *m))
        t += dt

    def still(sec):
        for _ in range(int(sec * rate)):
            emit([0.0, 0.0, 0.0])

    still(30.0)
    for _ in range(a.poses):
        ax = unit([rnd.gauss(0, 1) for _ in range(3)])
        theta = math.radians(rnd.uniform(60, 150)) * rnd.choice((-1, 1))
        T = rnd.uniform(1.5, 3.0)
        for r, d in hand_turn.turn_samples(theta, T, rate):
            C = matmul(C, hand_turn.rotation(ax, d))
            emit([r * ax[0], r * ax[1], r * ax[2]])
        still(rnd.uniform(4.0, 7.0))
    os.makedirs(a.folder, exist_ok=True)
    open(os.path.join(a.folder, "acc.txt"), "w").writelines(rows["accel"])
    open(os.path.join(a.folder, "gyro.txt"), "w").writelines(rows["gyro"])
    json.dump(truth, open(os.path.join(a.folder, "truth.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
