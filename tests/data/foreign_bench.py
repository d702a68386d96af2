#!/usr/bin/env python3
"""An independent bench-recording generator that knows only ../shared/spec/recording-format.md.

It plays "another tool": its own gravity formula (Somigliana), its own rotation code, the IMU
output as increments at 200 Hz, the reference at 50 Hz, columns in another order plus unknown
columns and comments, and time gaps between steps. It writes OUT/{meta.json,imu.csv,reference.csv}
and OUT/truth.json (coefficients.json schema) with the unit's errors.
Usage: foreign_bench.py OUT [SEED]
"""
import json, math, os, random, sys

out = sys.argv[1]
rnd = random.Random(int(sys.argv[2]) if len(sys.argv) > 2 else 1)
os.makedirs(out, exist_ok=True)
LAT, LON, H = 48.1, 11.6, 520.0
IMU_HZ, REF_HZ = 200.0, 50.0
OMEGA = 7.292115e-5
phi = math.radians(LAT)
s2 = math.sin(phi) ** 2
g = 9.7803253359 * (1 + 0.00193185265241 * s2) / math.sqrt(1 - 0.00669437999013 * s2) - 3.086e-6 * H
w_ie_n = [OMEGA * math.cos(phi), 0.0, -OMEGA * math.sin(phi)]

def rot(axis, a):
    c, s = math.cos(a), math.sin(a)
    if axis == 0: return [[1, 0, 0], [0, c, -s], [0, s, c]]
    if axis == 1: return [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    return [[c, -s, 0], [s, c, 0], [0, 0, 1]]

def mul(A, B): return [[sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
def mv(A, v): return [sum(A[i][k] * v[k] for k in range(3)) for i in range(3)]
def tr(A): return [[A[j][i] for j in range(3)] for i in range(3)]

# The unit (spec convention: measured = (I + M) true + b).
bg = [rnd.gauss(0, 3e-3) for _ in range(3)]
ba = [rnd.gauss(0, 0.15) for _ in range(3)]
Mg = [[rnd.gauss(0, 4e-3 if i == j else 4e-4) for j in range(3)] for i in range(3)]
Ma = [[rnd.gauss(0, 4e-3 if i == j else 4e-4) for j in range(3)] for i in range(3)]
def meas(M, b, x): return [x[i] + sum(M[i][j] * x[j] for j in range(3)) + b[i] for i in range(3)]

# Orientations C(IMU->NED): each IMU axis down and up, plus two tilted ones.
def axis_down(k, sign):
    # rotation taking IMU axis k to NED down (sign +1) or up (-1)
    if k == 2: return rot(0, 0.0) if sign > 0 else rot(0, math.pi)
    if k == 0: return rot(1, -math.pi / 2 * sign)   # x -> down for sign +1
    return rot(0, math.pi / 2 * sign)               # y -> down for sign +1
steps = []
for k in range(3):
    for sgn in (1, -1):
        steps.append(("static", axis_down(k, sgn), None, None))
steps.append(("static", mul(rot(2, 0.7), mul(rot(1, 0.5), rot(0, 0.9))), None, None))
steps.append(("static", mul(rot(2, -1.1), mul(rot(1, -0.4), rot(0, 2.2))), None, None))
for k in range(3):
    for rate in (100.0, -100.0, 250.0, -250.0):
        # rotate about IMU axis k with that axis pointing up
        steps.append(("rate", axis_down(k, -1), k, math.radians(rate)))

imu = open(os.path.join(out, "imu.csv"), "w")
ref = open(os.path.join(out, "reference.csv"), "w")
imu.write("# foreign tool: increments over the interval ending at t_s\n")
imu.write("dvz_m_s,t_s,dax_rad,day_rad,daz_rad,dvx_m_s,dvy_m_s,status\n")
ref.write("# foreign tool reference\nstep,t_s,fx_m_s2,fy_m_s2,fz_m_s2,wx_rad_s,wy_rad_s,wz_rad_s,operator\n")
t = 10.0
dt = 1.0 / IMU_HZ
ratio = int(IMU_HZ / REF_HZ)
for si, (kind, C0, k, rate) in enumerate(steps):
    n = int(12.0 * IMU_HZ)
    for i in range(n + 1):
        tt = t + i * dt          # end of the interval
        tm = tt - 0.5 * dt       # its middle
        if kind == "static":
            Cbn = C0
            w_body = [0.0, 0.0, 0.0]
        else:
            Cbn = mul(C0, rot(k, rate * (tm - t)))
            w_body = [0.0, 0.0, 0.0]
            w_body[k] = rate
        Cnb = tr(Cbn)
        w = [w_body[j] + x for j, x in enumerate(mv(Cnb, w_ie_n))]
        f = mv(Cnb, [0.0, 0.0, -g])
        if i % ratio == 0:
            # reference at the sample instant tt (rates and specific force at that instant)
            if kind == "static":
                wr, fr = w, f
            else:
                Cnb_t = tr(mul(C0, rot(k, rate * (tt - t))))
                wr = [w_body[j] + x for j, x in enumerate(mv(Cnb_t, w_ie_n))]
                fr = mv(Cnb_t, [0.0, 0.0, -g])
            ref.write("%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,bob\n" % (si, tt, fr[0], fr[1], fr[2], wr[0], wr[1], wr[2]))
        if i == 0:
            continue
        mg = meas(Mg, bg, w)
        ma = meas(Ma, ba, f)
        da = [(mg[j] + rnd.gauss(0, 2e-3)) * dt for j in range(3)]
        dv = [(ma[j] + rnd.gauss(0, 2e-2)) * dt for j in range(3)]
        imu.write("%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,ok\n" % (dv[2], tt, da[0], da[1], da[2], dv[0], dv[1]))
    t += n * dt + 3.0  # 3 s gap: the foreign tool did not record the moves
imu.close(); ref.close()
json.dump({"format": "calbench-recording/1", "kind": "bench",
           "device": {"model": "ADIS16488A", "serial": "FOREIGN-1"},
           "site": {"lat_deg": LAT, "lon_deg": LON, "h_m": H}, "imu_rate_hz": IMU_HZ,
           "notes": "written by tests/data/foreign_bench.py", "tool": {"name": "foreign", "version": 3}},
          open(os.path.join(out, "meta.json"), "w"), indent=1)
z3 = [[0.0] * 3 for _ in range(3)]
json.dump({"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": "FOREIGN-1"},
           "gyro": {"bias": bg, "M": Mg, "sigma_bias": [0, 0, 0], "sigma_M": z3},
           "accel": {"bias": ba, "M": Ma, "sigma_bias": [0, 0, 0], "sigma_M": z3}},
          open(os.path.join(out, "truth.json"), "w"), indent=1)
