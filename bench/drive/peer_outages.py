#!/usr/bin/env python3
"""Side by side with a peer GNSS/INS filter (issue 34 item 8): calbench and KF-GINS on the same
simulated drives with GNSS outages made by removing fixes, each tool's largest horizontal error
against the truth during each outage, as a Markdown table on standard output.

Per seed: `calbench simulate drive` (the route, --truth random, --device-class) -> a copy whose gnss.csv lacks the
fixes inside the outage windows -> (a) `calbench fit drive COPY --aiding gnss --series S
--series-every 0.02 --outages none`, with --obs pos,vel (the default) and --obs pos (the forward
pass's navigation solution, also between fixes) and
(b) `calbench export kf-gins COPY` then KF-GINS on it (an external program, built separately:
--kf-gins BINARY), once with the starter configuration and once with `--standstill S` (its initial
gyro bias measured on the opening standstill, as one initialises a filter that cannot align itself). Both are scored at the reference body origin (the antenna: calbench's MEMS
position - C_nb(vehicle) * lever arm with its own mounting estimate; KF-GINS's IMU position +
C_nb * antenna lever arm) against reference.csv, the simulator's reference (FOG-grade, 2 cm white
error), at the reference epochs (50 Hz) inside each window. Truth only scores: neither tool reads it
(KF-GINS's starter configuration takes its initial state from reference.csv at the start, see
docs/validation/peer-kf-gins.md).

Usage: bench/drive/peer_outages.py --kf-gins /path/to/KF-GINS [--peer "i2Nav-WHU/KF-GINS COMMIT"]
       [--seeds 1,2,3,4,5 [--seeds 6,7,8,9,10 ...]] [--device-class ADIS16488A] [--route bench/routes/rtk_town.toml]
       [--outages 60:90,95:125,195:225] [--standstill 25] [--work DIR]
Each seed set is a section ("## CLASS, seeds ...": the outages, then the summary, whose rows name
the class and the seeds, so that the output of several runs can stand in one file); with more than
one --seeds, a last section "## CLASS, all seeds" pools their outages, with the paired comparison
against KF-GINS with the standstill gyro bias (outages below it, the sign test's p).
Environment: CALBENCH (the executable; default build/calbench).
"""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

A_WGS84, E2_WGS84 = 6378137.0, 6.69437999014e-3
# calbench with the fixes' position and velocity (its default with GNSS aiding), calbench with
# position only (what KF-GINS's .pos file carries), KF-GINS with the starter configuration (gyro
# bias 0, σ the raw-data prior), KF-GINS with its initial gyro bias from the opening standstill.
TOOLS = ("calbench", "calbench pos", "KF-GINS", "KF-GINS still")


def rows(path):
    """The data rows of a calbench CSV (comment lines skipped) as dicts of floats."""
    with open(path) as f:
        lines = [l for l in f if not l.startswith("#")]
    return [{k: float(v) for k, v in r.items() if v not in ("", None)} for r in csv.DictReader(lines)]


def dcm(roll, pitch, yaw):
    """C(body -> NED) = Rz(yaw) Ry(pitch) Rx(roll), angles in degrees (recording-format.md)."""
    r, p, y = (math.radians(a) for a in (roll, pitch, yaw))
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr]]


def mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def apply(a, v):
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def radii(lat_deg, h):
    s = math.sin(math.radians(lat_deg))
    w = math.sqrt(1 - E2_WGS84 * s * s)
    return A_WGS84 * (1 - E2_WGS84) / w ** 3 + h, (A_WGS84 / w + h) * math.cos(math.radians(lat_deg))


def shift(lat, lon, h, d_ned):
    """Geodetic position moved by a small NED vector (m)."""
    rm, rn = radii(lat, h)
    return lat + math.degrees(d_ned[0] / rm), lon + math.degrees(d_ned[1] / rn), h - d_ned[2]


def horizontal(lat, lon, h, lat_t, lon_t):
    rm, rn = radii(lat_t, h)
    return math.hypot(math.radians(lat - lat_t) * rm, math.radians(lon - lon_t) * rn)


def key(t):
    return round(t * 1000)


def run(cmd, log):
    with open(log, "w") as f:
        r = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT)
    if r.returncode != 0:
        sys.exit("peer_outages: %s failed (exit %d), log %s" % (" ".join(cmd), r.returncode, log))


def outage_copy(src, dst, windows):
    """The recording with the fixes inside the windows (a < t <= b) removed from gnss.csv."""
    os.makedirs(dst, exist_ok=True)
    for f in ("meta.json", "imu.csv", "reference.csv"):
        shutil.copyfile(os.path.join(src, f), os.path.join(dst, f))
    kept = removed = 0
    with open(os.path.join(src, "gnss.csv")) as f, open(os.path.join(dst, "gnss.csv"), "w") as g:
        header = True
        for line in f:
            if line.startswith("#") or header:
                header = header and line.startswith("#")
                g.write(line)
                continue
            t = float(line.split(",", 1)[0])
            if any(a < t <= b for a, b in windows):
                removed += 1
            else:
                kept += 1
                g.write(line)
    return kept, removed


def calbench_antenna(series_path, lever):
    """t -> (lat, lon, h) of the antenna from the forward-pass series (MEMS position and attitude)."""
    out = {}
    for r in rows(series_path):
        C_nm = dcm(r["roll_deg"], r["pitch_deg"], r["yaw_deg"])  # MEMS axes -> NED
        C_mb = dcm(r["mount_roll_deg"], r["mount_pitch_deg"], r["mount_yaw_deg"])  # MEMS -> body
        C_nb = mul(C_nm, transpose(C_mb))
        d = apply(C_nb, lever)
        out[key(r["t_s"])] = shift(r["lat_deg"], r["lon_deg"], r["h_m"], [-d[0], -d[1], -d[2]])
    return out


def kfgins_antenna(nav_path, lever):
    """t -> (lat, lon, h) of the antenna from KF_GINS_Navresult.nav (IMU position, IMU = body frame)."""
    out = {}
    with open(nav_path) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            if len(v) < 11:
                continue
            d = apply(dcm(v[8], v[9], v[10]), lever)
            out[key(v[1])] = shift(v[2], v[3], v[4], [-d[0], -d[1], -d[2]])
    return out


def largest_error(sol, truth, a, b):
    worst, n = 0.0, 0
    for r in truth:
        if a <= r["t_s"] <= b:
            p = sol.get(key(r["t_s"]))
            if p is None:
                continue
            worst = max(worst, horizontal(p[0], p[1], p[2], r["lat_deg"], r["lon_deg"]))
            n += 1
    return worst if n else float("nan"), n


def median(v):
    s = sorted(v)
    n = len(s)
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


def drive(exe, a, work, windows, seed):
    """One seed: simulate (once per --work folder), remove the fixes, run both tools, score them.
    Returns [(seed, T0, T1, {tool: largest error, m})], one per window."""
    d = os.path.join(work, "%s_s%d" % (a.device_class, seed))
    if not os.path.exists(os.path.join(d, "meta.json")):
        run([exe, "simulate", "drive", "--route", a.route, "--truth", "random", "--seed", str(seed), "--device-class",
             a.device_class, "--out", d], d + ".sim.log")
    c = d + "_outages"
    outage_copy(d, c, windows)
    lever = json.load(open(os.path.join(d, "meta.json")))["mounting"]["lever_arm_m"]
    sols = {}
    for tool, obs in (("calbench", "pos,vel"), ("calbench pos", "pos")):
        series = "%s_series_%s.csv" % (c, obs.replace(",", "_"))
        run([exe, "fit", "drive", c, "--aiding", "gnss", "--obs", obs, "--series", series, "--series-every", "0.02",
             "--outages", "none", "--out", "%s_RESULT_%s.json" % (c, obs.replace(",", "_"))], series + ".log")
        sols[tool] = calbench_antenna(series, lever)
    for tool, extra in (("KF-GINS", []), ("KF-GINS still", ["--standstill", str(a.standstill)])):
        k = c + ("_kf" if not extra else "_kf_still")
        run([exe, "export", "kf-gins", c, "--out", k, "--force"] + extra, k + ".export.log")
        run([a.kf_gins, os.path.join(k, "kf-gins.yaml")], k + ".run.log")
        sols[tool] = kfgins_antenna(os.path.join(k, "KF_GINS_Navresult.nav"), lever)
    truth = rows(os.path.join(d, "reference.csv"))
    return [(seed, w0, w1, {tool: largest_error(sol, truth, w0, w1)[0] for tool, sol in sols.items()})
            for (w0, w1) in windows]


def sign_test(wins, n):
    """Two-sided p of the sign test: the chance of a split at least this uneven in n fair coin tosses."""
    k = min(wins, n - wins)
    return min(1.0, 2.0 * sum(math.comb(n, j) for j in range(k + 1)) / 2.0 ** n) if n else 1.0


def paired(pairs):
    """(below, n, p) of calbench against the peer over (calbench, peer) pairs, compared as printed (to
    the centimetre): ties are dropped from n, as the sign test does."""
    below = sum(1 for c, k in pairs if round(c, 2) < round(k, 2))
    n = sum(1 for c, k in pairs if round(c, 2) != round(k, 2))
    return below, n, sign_test(below, n)


def p_text(p):
    return "%.3f" % p if p >= 0.001 else "< 0.001"


NAMES = ("calbench, pos+vel fixes", "calbench, position only", "KF-GINS, position",
         "KF-GINS, position, gyro bias from the opening %g s")
POOLED = "all seeds"


def report(a, which, table, route):
    """The Markdown section of one seed set: the outages and the summary; for the pooled set
    (POOLED) the summary only, with the paired comparisons."""
    names = NAMES[:3] + (NAMES[3] % a.standstill,)
    print("## %s, %s" % (a.device_class, which))
    print()
    if which == POOLED:
        seeds = sorted({r[0] for r in table})
        print("The %d outages (%d drives) of the seed sets above together. Paired against KF-GINS with the standstill" % (len(table), len(seeds)))
        print("gyro bias (its better start): per outage, is calbench's largest error below KF-GINS's; per drive, is the")
        print("mean of its outages' largest errors below? Compared as printed (to the centimetre); ties are left out")
        print("of the count. The sign test's two-sided p is the chance of a split at least this uneven if neither tool")
        print("were better. The outages of one drive share its unit and its alignment, so the per-drive test is the")
        print("one that treats its samples as independent.")
    else:
        print("Route `%s`, %s, `--truth random --device-class %s` (raw: no coefficient set), GNSS aiding only." % (route, which, a.device_class))
        print("Outages: the fixes with T0 < t <= T1 removed from gnss.csv for both tools. Error: largest horizontal")
        print("distance of the antenna (reference body origin) from reference.csv during the window, m.")
        print("KF-GINS (%s) cannot align itself: `export kf-gins` starts it from reference.csv's state at the first" % a.peer)
        print("epoch; calbench levels itself on the opening standstill and finds its heading from the fixes.")
        print()
        print("| seed | outage (s) | %s |" % " | ".join(n + " (m)" for n in names))
        print("|---:|---|" + "---:|" * len(names))
        for seed, w0, w1, e in table:
            print("| %d | %g–%g | %s |" % (seed, w0, w1, " | ".join("%.2f" % e[t] for t in TOOLS)))
    print()
    if which == POOLED:
        print("| tool (%s, %s) | median of the per-outage maxima (m) | largest (m) | mean (m) | outages below KF-GINS with the standstill gyro bias | sign test p, outages | drives below it | sign test p, drives |"
              % (a.device_class, which))
        print("|---|---:|---:|---:|---:|---:|---:|---:|")
    else:
        print("| tool (%s, %s) | median of the per-outage maxima (m) | largest (m) | outages at or below the better KF-GINS run |"
              % (a.device_class, which))
        print("|---|---:|---:|---:|")
    n = len(table)
    for tool, name in zip(TOOLS, names):
        e = [r[3][tool] for r in table]
        cells = ["%.2f" % median(e), "%.2f" % max(e)]
        if which == POOLED:
            cells.append("%.2f" % (sum(e) / n))
            if tool.startswith("KF-GINS"):
                cells += ["", "", "", ""]
            else:
                below, m, p = paired([(r[3][tool], r[3]["KF-GINS still"]) for r in table])
                drives = {}
                for r in table:
                    drives.setdefault(r[0], []).append((r[3][tool], r[3]["KF-GINS still"]))
                db, dm, dp = paired([(sum(c for c, _ in v) / len(v), sum(k for _, k in v) / len(v)) for v in drives.values()])
                cells += ["%d of %d" % (below, m), p_text(p), "%d of %d" % (db, dm), p_text(dp)]
        else:
            cells.append("" if tool.startswith("KF-GINS") else "%d of %d" % (
                sum(1 for r in table if r[3][tool] <= min(r[3]["KF-GINS"], r[3]["KF-GINS still"])), n))
        print("| %s, %s, %s | %s |" % (name, a.device_class, which, " | ".join(cells)))
    print()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kf-gins", required=True, help="the KF-GINS executable")
    ap.add_argument("--seeds", action="append",
                    help="simulation seeds of one seed set (default 1,2,3,4,5); repeat for several sets: a section "
                         "each, then the pooled summary of all of them")
    ap.add_argument("--device-class", default="ADIS16488A",
                    help="the simulated unit's IMU class (simulate drive --device-class; both filters take their noise from it "
                         "through meta.json; default ADIS16488A)")
    ap.add_argument("--route", default="bench/routes/rtk_town.toml", help="route TOML (default rtk_town: RTK 5 Hz, 1.5 cm)")
    ap.add_argument("--outages", default="60:90,95:125,195:225", help="outage windows T0:T1 in s (fixes removed)")
    ap.add_argument("--standstill", type=float, default=25.0,
                    help="seconds of the opening standstill for the second KF-GINS run's gyro bias (default 25; rtk_town stands 30 s)")
    ap.add_argument("--peer", default="KF-GINS", help="how the KF-GINS build is named in the output, e.g. its commit")
    ap.add_argument("--work", help="working folder to keep (default: a temporary one, removed)")
    a = ap.parse_args()
    exe = os.environ.get("CALBENCH", "build/calbench")
    try:
        windows = [tuple(float(x) for x in w.split(":")) for w in a.outages.split(",")]
        seed_sets = [[int(s) for s in seeds.split(",")] for seeds in (a.seeds or ["1,2,3,4,5"])]
    except ValueError:
        ap.error("--outages T0:T1,... and --seeds N,... must be numbers")
    if any(len(w) != 2 or not w[0] < w[1] for w in windows):
        ap.error("--outages: each window T0:T1 with T0 < T1")
    every = [s for seeds in seed_sets for s in seeds]
    if len(set(every)) != len(every):
        ap.error("--seeds: a seed given twice (%s); the pooled summary would count its drive twice"
                 % ", ".join(sorted({str(s) for s in every if every.count(s) > 1})))
    work = a.work or tempfile.mkdtemp(prefix="peer_outages.")
    os.makedirs(work, exist_ok=True)
    pooled = []
    for seeds in seed_sets:
        table = [row for seed in seeds for row in drive(exe, a, work, windows, seed)]
        pooled += table
        report(a, "seeds " + ",".join(str(s) for s in seeds), table, os.path.basename(a.route))
    if len(seed_sets) > 1:
        report(a, POOLED, pooled, os.path.basename(a.route))
    if not a.work:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
