#!/usr/bin/env python3
"""GNSS-only consistency acceptance of the in-motion filter (issue 34 item 3; docs/in-motion.md,
"Adaptive process noise and the robust gate").

Per route, fix grade and seed: `calbench simulate drive --truth random`, reference.csv removed (a
GNSS-only recording), `calbench fit drive --aiding gnss --obs pos,vel`, scored against truth.json
(the truth only scores): share of fixes rejected, forced covariance widenings, heading
re-alignments after the first, mean NIS over its expectation per observation, coefficients (24) and
mounting angles (3) within 3 sigma of the truth. Prints a Markdown table (stdout).

Usage: bench/drive/gnss_consistency.py CALBENCH [--seeds 1,2,3,4,5] [--routes short,rtk_town]
       [--grades rtk,rtk10,1hz] [--classes ADIS16488A,ICM-42688-P,...] [--obs pos,vel] [--extra-args "..."]
       [--sim-args "--logger-read-hz R --gnss-velocity-from-positions"]
       [--real DIR ...]
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROUTES = os.path.join(HERE, "..", "routes")
GRADES = {  # the [gnss] table written into the route: RTK-grade and single-point-grade fixes
    "rtk": "[gnss]\nrate_hz = 5.0\nsigma_h_m = 0.015\nsigma_v_m = 0.03\nsigma_vel_m_s = 0.02\n",
    "rtk10": "[gnss]\nrate_hz = 10.0\nsigma_h_m = 0.01\nsigma_v_m = 0.02\nsigma_vel_m_s = 0.01\n",
    "1hz": "[gnss]\nrate_hz = 1.0\nsigma_h_m = 1.0\nsigma_v_m = 2.0\nsigma_vel_m_s = 0.05\n",
}


def route_with_grade(route, grade, out):
    text = open(os.path.join(ROUTES, route + ".toml")).read()
    text = re.sub(r"\[gnss\][^\[]*", GRADES[grade] + "\n", text, count=1)
    open(out, "w").write(text)


def score(result, truth=None):
    r = json.load(open(result))
    cons = r["consistency"]
    used = sum(c["epochs"] for c in cons.values())
    rej = sum(c["rejected"] for c in cons.values())
    forced = sum(c["forced"] for c in cons.values())
    al = r.get("alignment", {})
    realign = al.get("realignments", 0)
    row = {
        "rejected_pct": 100.0 * rej / max(1, used + rej + forced),
        "widenings": al.get("covariance_widenings", 0),
        "realign_after_first": max(0, realign - 1),
        "heading": al.get("heading", {}).get("t_s"),
        "nis": {k: c["mean_nis"] / c["expected_nis"] for k, c in cons.items()},
        "q_max": r.get("adaptive_noise", {}).get("scale_max", 1.0),
    }
    if truth:
        t = json.load(open(truth))
        c = r["coefficients"]
        n = ok = 0
        for tri in ("gyro", "accel"):
            for i in range(3):
                pairs = [(c[tri]["bias"][i], c[tri]["sigma_bias"][i], t[tri]["bias"][i])]
                pairs += [(c[tri]["M"][i][j], c[tri]["sigma_M"][i][j], t[tri]["M"][i][j]) for j in range(3)]
                for v, s, tv in pairs:
                    n += 1
                    ok += s is not None and s > 0 and abs(v - tv) <= 3 * s
        m = r["mounting_rpy_deg"]
        mn = mok = 0
        for i in range(3):
            d = (m["value"][i] - t["mounting"]["rpy_deg"][i] + 180) % 360 - 180
            mn += 1
            mok += abs(d) <= 3 * m["sigma"][i]
        row.update(coef=(ok, n), mount=(mok, mn))
    return row


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("calbench")
    ap.add_argument("--seeds", default="1,2,3,4,5")
    ap.add_argument("--routes", default="short,rtk_town")
    ap.add_argument("--grades", default="rtk,rtk10,1hz")
    ap.add_argument("--classes", default="ADIS16488A", help="device classes to simulate (simulate drive --device-class)")
    ap.add_argument("--obs", default="pos,vel")
    ap.add_argument("--extra-args", default="")
    ap.add_argument("--sim-args", default="",
                    help="extra simulate drive options, e.g. \"--logger-read-hz 300 --gnss-velocity-from-positions\" "
                         "(a real logger and receiver, docs/in-motion.md \"Real loggers\")")
    ap.add_argument("--real", nargs="*", default=[])
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="gnss_consistency.")
    rows = []
    try:
        for cls in a.classes.split(","):
          for route in a.routes.split(","):
            for grade in a.grades.split(","):
                for seed in a.seeds.split(","):
                    rt = os.path.join(work, "route.toml")
                    route_with_grade(route, grade, rt)
                    d = os.path.join(work, "drive")
                    shutil.rmtree(d, ignore_errors=True)
                    subprocess.run([a.calbench, "simulate", "drive", "--route", rt, "--truth", "random", "--seed", seed,
                                    "--device-class", cls, "--out", d] + a.sim_args.split(), check=True, stdout=subprocess.DEVNULL)
                    os.remove(os.path.join(d, "reference.csv"))
                    res = os.path.join(work, "r.json")
                    subprocess.run([a.calbench, "fit", "drive", d, "--aiding", "gnss", "--obs", a.obs, "--out", res]
                                   + a.extra_args.split(), check=True, stdout=subprocess.DEVNULL)
                    s = score(res, os.path.join(d, "truth.json"))
                    s.update(name="%s, %s %s seed %s" % (cls, route, grade, seed))
                    rows.append(s)
                    print(s, file=sys.stderr)
        for d in a.real:
            res = os.path.join(work, "r.json")
            subprocess.run([a.calbench, "fit", "drive", d, "--aiding", "gnss", "--out", res] + a.extra_args.split(),
                           check=True, stdout=subprocess.DEVNULL)
            s = score(res)
            s.update(name="real: " + os.path.basename(os.path.normpath(d)))
            rows.append(s)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print("| drive | fixes rejected | forced widenings | re-alignments after the first | mean NIS / expected (pos, vel) "
          "| noise scale max | coefficients within 3σ | mounting within 3σ |")
    print("|---|---|---|---|---|---|---|---|")
    for s in rows:
        nis = ", ".join("%.2f" % s["nis"][k] for k in ("position", "velocity") if k in s["nis"])
        coef = "%d/%d" % s["coef"] if "coef" in s else "—"
        mount = "%d/%d" % s["mount"] if "mount" in s else "—"
        print("| %s | %.1f %% | %d | %d | %s | %.3g | %s | %s |" % (s["name"], s["rejected_pct"], s["widenings"],
                                                                  s["realign_after_first"], nis, s["q_max"], coef, mount))
    sim = [s for s in rows if "coef" in s]
    groups = {}
    for s in sim:
        groups.setdefault(s["name"].split(",")[0], []).append(s)
    if len(groups) > 1:
        groups["all classes"] = sim
    for name, g in groups.items():
        c = [sum(s["coef"][i] for s in g) for i in (0, 1)]
        m = [sum(s["mount"][i] for s in g) for i in (0, 1)]
        nis = [v for s in g for k, v in s["nis"].items() if k in ("position", "velocity")]
        print("\n%s, %d simulated drives: coefficients within 3σ %d/%d (%.1f %%), mounting %d/%d (%.1f %%); fixes "
              "rejected at most %.1f %%; forced widenings %d; re-alignments after the first %d; mean NIS / expected "
              "%.2f–%.2f." % (name, len(g), c[0], c[1], 100.0 * c[0] / c[1], m[0], m[1], 100.0 * m[0] / m[1],
                             max(s["rejected_pct"] for s in g), sum(s["widenings"] for s in g),
                             sum(s["realign_after_first"] for s in g), min(nis), max(nis)))

if __name__ == "__main__":
    main()
