#!/usr/bin/env python3
"""The filters' state against the truth at given times of the drives bench/drive/peer_outages.py
kept (--work DIR): per seed and time, each filter's attitude error (rotation vector of the MEMS
attitude against the truth's, NED, deg: north/east = tilt, down = heading), calbench's own heading
sigma, and the gyro and accelerometer bias errors in MEMS axes (calbench: its total drift, bias +
in-run part; KF-GINS: its IMU-error file, turned from its frame by the nominal mounting). Truth only
scores: truth.json (the unit's errors and true mounting) and reference.csv. Diagnosis of the
outages (docs/in-motion.md, "Side by side with KF-GINS through GNSS outages").

Usage: bench/drive/peer_states.py DIR SEED T1,T2,... [--device-class ADIS16488A]
"""
import argparse
import bisect
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import peer_outages as po  # noqa: E402  (the drives' layout, CSV reader and rotations)


def rotvec_deg(C):
    """The rotation vector (deg) of a DCM close to the identity or not."""
    ang = math.acos(max(-1.0, min(1.0, (C[0][0] + C[1][1] + C[2][2] - 1) / 2)))
    v = [C[2][1] - C[1][2], C[0][2] - C[2][0], C[1][0] - C[0][1]]
    s = math.sin(ang)
    k = ang / (2 * s) if s > 1e-12 else 0.5
    return [math.degrees(k * x) for x in v]


def nearest(rows, t):
    ts = [r["t_s"] for r in rows]
    i = bisect.bisect_left(ts, t)
    return rows[min((j for j in (i - 1, i) if 0 <= j < len(rows)), key=lambda j: abs(ts[j] - t))]


def kfgins(folder):
    nav, err = [], []
    with open(os.path.join(folder, "KF_GINS_Navresult.nav")) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            nav.append({"t_s": v[1], "rpy": v[8:11]})
    with open(os.path.join(folder, "KF_GINS_IMU_ERR.txt")) as f:
        for line in f:
            v = [float(x) for x in line.split()]  # deg/h, mGal
            err.append({"t_s": v[0], "bg": v[1:4], "ba": [x / 1e5 / 9.80665 * 1e3 for x in v[4:7]]})
    return nav, err


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("work", help="the --work folder of bench/drive/peer_outages.py")
    ap.add_argument("seed", type=int, help="the seed")
    ap.add_argument("times", help="times, s, comma-separated (e.g. the outage starts 60,95,195)")
    ap.add_argument("--device-class", default="ADIS16488A", help="the class the drives were simulated with (default ADIS16488A)")
    a = ap.parse_args()
    try:
        times = [float(x) for x in a.times.split(",")]
    except ValueError:
        ap.error("times: numbers, comma-separated")
    d = os.path.join(a.work, "%s_s%d" % (a.device_class, a.seed))
    c = d + "_outages"
    if not os.path.exists(os.path.join(d, "truth.json")):
        print("peer_states: %s: no truth.json (run bench/drive/peer_outages.py --work %s first)" % (d, a.work), file=sys.stderr)
        sys.exit(2)
    truth = json.load(open(os.path.join(d, "truth.json")))
    meta = json.load(open(os.path.join(d, "meta.json")))
    ref = po.rows(os.path.join(d, "reference.csv"))
    C_mb_true = po.dcm(*truth["mounting"]["rpy_deg"])
    C_mb_nom = po.dcm(*meta["mounting"]["rpy_deg"])
    bg = [x * 180 / math.pi * 3600 for x in truth["gyro"]["bias"]]
    ba = [x / 9.80665 * 1e3 for x in truth["accel"]["bias"]]
    series = {k: po.rows(c + "_series_%s.csv" % k) for k in ("pos_vel", "pos") if os.path.exists(c + "_series_%s.csv" % k)}
    kf = {k: kfgins(c + s) for k, s in (("KF-GINS", "_kf"), ("KF-GINS still", "_kf_still")) if os.path.isdir(c + s)}
    print("seed %d (%s): true gyro bias %s deg/h, accel bias %s mg (MEMS axes)" % (
        a.seed, a.device_class, " ".join("%.0f" % x for x in bg), " ".join("%.1f" % x for x in ba)))
    print("| t (s) | filter | attitude error N, E, D (deg) | heading sigma (deg) | gyro bias error x, y, z (deg/h) | accel bias error x, y, z (mg) |")
    print("|---:|---|---|---:|---|---|")
    for t in times:
        r = nearest(ref, t)
        C_nm_true = po.mul(po.dcm(r["roll_deg"], r["pitch_deg"], r["yaw_deg"]), C_mb_true)
        for k, rows in series.items():
            s = nearest(rows, t)
            phi = rotvec_deg(po.mul(po.dcm(s["roll_deg"], s["pitch_deg"], s["yaw_deg"]), po.transpose(C_nm_true)))
            eb = [s["gyro_total_%s_dph" % x] - bg[i] for i, x in enumerate("xyz")]
            ea = [s["accel_total_%s_mg" % x] - ba[i] for i, x in enumerate("xyz")]
            print("| %g | calbench %s | %.2f, %.2f, %.2f | %.2f | %.1f, %.1f, %.1f | %.2f, %.2f, %.2f |" % (
                t, k.replace("_", ","), *phi, s["sigma_yaw_deg"], *eb, *ea))
        for k, (nav, err) in kf.items():
            s, e = nearest(nav, t), nearest(err, t)
            C_nm = po.mul(po.dcm(*s["rpy"]), C_mb_nom)  # its IMU frame is the nominally mounted MEMS
            phi = rotvec_deg(po.mul(C_nm, po.transpose(C_nm_true)))
            gm, am = po.apply(po.transpose(C_mb_nom), e["bg"]), po.apply(po.transpose(C_mb_nom), e["ba"])
            print("| %g | %s | %.2f, %.2f, %.2f | | %.1f, %.1f, %.1f | %.2f, %.2f, %.2f |" % (
                t, k, *phi, *[gm[i] - bg[i] for i in range(3)], *[am[i] - ba[i] for i in range(3)]))


if __name__ == "__main__":
    main()
