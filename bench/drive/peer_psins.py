#!/usr/bin/env python3
"""calbench `fit drive` and PSINS's own transfer alignment on PSINS's real FOG/MEMS vehicle drive
(issue 53 item 6: every real recording beside a peer; docs/validation/peer-psins.md).

PSINS: the toolbox's demo demos/test_align_transfer_fog_mems.m, unchanged, in GNU Octave, through
the headless shims of tests/peer/psins (they print the demo's last estimate instead of drawing it).
calbench: `fit drive ../shared/data/psins-vehicle-100s --device-class ADIS16488A` (the recording
converted from the same .mat). Both estimate the MEMS gyro drift, accelerometer bias and the
MEMS-to-FOG mounting from the FOG INS's attitude and velocity over the same 100 s; the .mat also
holds the toolbox author's own values (eb0, db0, mu0), printed as a third column.

Usage: bench/drive/peer_psins.py CALBENCH --psins PSINS_CHECKOUT [--data DIR] [--octave octave]
  | scripts/validation-stamp peer-psins.md TITLE COMMAND
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def run_psins(psins, octave):
    env = dict(os.environ, PSINS_ROOT=os.path.abspath(psins))
    t0 = time.monotonic()
    p = subprocess.run([octave, "--no-gui", "--quiet", os.path.join(ROOT, "tests/peer/psins/run_fog_mems.m")],
                       env=env, capture_output=True, text=True, timeout=1800)
    wall = time.monotonic() - t0
    out = {}
    for line in p.stdout.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0].replace("_", "").isalnum():
            try:
                out[parts[0]] = [float(x) for x in parts[1:]]
            except ValueError:
                pass
    if "eb_deg_h" not in out:
        sys.exit("peer_psins: the PSINS run printed no estimate (exit %d):\n%s%s" % (p.returncode, p.stdout[-2000:], p.stderr[-2000:]))
    return out, wall


def dcm(rpy_deg):
    r, p, y = (math.radians(v) for v in rpy_deg)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return [[cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
            [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
            [-sp, sr * cp, cr * cp]]


def small_rotation_deg(nominal, estimate):
    """The rotation from the estimated to the nominal mounting, C_nom·C_estᵀ, as a rotation vector
    in MEMS axes (small angles), degrees."""
    a, b = dcm(nominal), dcm(estimate)
    R = [[sum(a[i][k] * b[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    return [math.degrees((R[2][1] - R[1][2]) / 2), math.degrees((R[0][2] - R[2][0]) / 2), math.degrees((R[1][0] - R[0][1]) / 2)]


def run_calbench(calbench, data):
    with tempfile.TemporaryDirectory() as d:
        t0 = time.monotonic()
        p = subprocess.run([calbench, "fit", "drive", data, "--device-class", "ADIS16488A", "--out", os.path.join(d, "R.json"), "--json"],
                           capture_output=True, text=True)
        wall = time.monotonic() - t0
        if p.returncode != 0:
            sys.exit("peer_psins: calbench fit drive failed (%d): %s" % (p.returncode, p.stderr[-2000:]))
        return json.loads(p.stdout), wall


def fmt3(v, prec):
    return ", ".join("%.*f" % (prec, x) for x in v)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("calbench")
    ap.add_argument("--psins", required=True, help="a PSINS checkout (git clone https://github.com/WangShanpeng/PSINS)")
    ap.add_argument("--data", default=os.path.join(ROOT, "..", "shared", "data", "psins-vehicle-100s"))
    ap.add_argument("--octave", default="octave")
    a = ap.parse_args()
    peer, peer_wall = run_psins(a.psins, a.octave)
    cb, cb_wall = run_calbench(a.calbench, a.data)
    dph = 180 / math.pi * 3600
    g, acc = cb["coefficients"]["gyro"], cb["coefficients"]["accel"]
    cb_eb = [x * dph for x in g["bias"]]
    cb_eb_s = [x * dph for x in g["sigma_bias"]]
    cb_db = [x / 9.80665 * 1e3 for x in acc["bias"]]
    cb_db_s = [x / 9.80665 * 1e3 for x in acc["sigma_bias"]]
    # A near-level drive holds f ≈ (0, 0, g) (z up): b and the column M·f are one offset to it, which
    # calbench splits by its priors and PSINS (no scale or skew states) takes as bias; compare the sum.
    M = acc["M"]
    cb_off = [cb_db[i] + M[i][2] * 1e3 for i in range(3)]  # M·g in mg is M·1000
    m = cb["mounting_rpy_deg"]
    cb_mu = small_rotation_deg(m["nominal"], m["value"])
    print("Both on the same 100 s of PSINS's FOG/MEMS vehicle drive (the MEMS axes as logged: x right, y forward, z up).")
    print("PSINS: its demo `test_align_transfer_fog_mems.m`, unchanged (21 states: attitude, velocity, gyro drift, accelerometer")
    print("bias, mounting, flexure; attitude and velocity matching at 10 Hz), its last estimate ± its filter's σ. calbench:")
    print("`fit drive --device-class ADIS16488A` (positions, velocities and attitudes of the FOG INS; bias, scale and skew of both")
    print("triads, mounting), its estimate ± σ. The author's values: eb0, db0, mu0 as stored in the toolbox's .mat.")
    print()
    print("| quantity | calbench | PSINS demo | the author's values (.mat) | calbench − PSINS |")
    print("|---|---|---|---|---|")
    rows = [
        ("gyro drift x, y, z (°/h)", cb_eb, cb_eb_s, peer["eb_deg_h"], peer["eb_sigma_deg_h"], peer.get("eb0_deg_h"), 1),
        ("accelerometer bias x, y, z (mg)", cb_db, cb_db_s, peer["db_mg"], peer["db_sigma_mg"], peer.get("db0_mg"), 2),
        ("accelerometer output offset at level, b + M·(0, 0, g) (mg)", cb_off, None, peer["db_mg"], peer["db_sigma_mg"], peer.get("db0_mg"), 2),
        ("mounting, small rotation x, y, z (°)", cb_mu, m["sigma"], peer["mu_deg"], peer["mu_sigma_deg"], peer.get("mu0_deg"), 3),
    ]
    for name, c, cs, p, ps, ref, prec in rows:
        diff = [x - y for x, y in zip(c, p)]
        cs_text = " ± " + fmt3(cs, prec) if cs else ""
        print("| %s | %s%s | %s ± %s | %s | %s |" % (name, fmt3(c, prec), cs_text, fmt3(p, prec), fmt3(ps, prec),
                                                      fmt3(ref, prec) if ref else "—", fmt3(diff, prec)))
    print()
    nis = cb["consistency"]
    print("calbench's NIS per observation / expected: " + ", ".join(
        "%s %.2f" % (k, v["mean_nis"] / v["expected_nis"]) for k, v in nis.items()) +
        "; wall time: calbench %.2f s, PSINS in Octave %.1f s (one run each, this machine)." % (cb_wall, peer_wall))
    print()
    print("calbench's mounting is read as the rotation C_nom·C_estᵀ in MEMS axes; it is estimated together with both triads'")
    print("skews, whose common rotation is held at its prior (fit drive's `common rotation` line), so it differs from a")
    print("filter without skews by up to that prior. The horizontal offsets trade against the mounting's tilt: 0.1° of tilt")
    print("is 1.7 mg of horizontal specific force.")


if __name__ == "__main__":
    main()
