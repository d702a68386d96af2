#!/usr/bin/env python3
"""Variants of IMU-TK's real Xsens multi-position recording (issue 55): short poses, other noise, no
opening still interval — acceptance data for `calbench fit multipos`, made without calbench's code.

Reads ../shared/data/imu_tk-xsens-multipos/xsens_acc.mat and xsens_gyro.mat (text rows `t x y z`
in raw counts), converts them with the nominal figures the tests use (accelerometer
(count − 32768)·0.0026808 m/s², gyro (count − 32768)·1.5979e-4 rad/s) and writes into OUT:

  acc.txt, gyro.txt   IMU-TK text files, rows `t x y z` in SI (s, m/s², rad/s), 100 Hz uniform time:
                      `calbench import imu-tk OUT/acc.txt OUT/gyro.txt --out REC --model M --serial S
                      --gravity 9.81744` reads them without count options.
  poses.json          what this script found, with no truth in it: the static intervals kept (output
                      time), the number of poses, the number of distinct gravity directions among
                      them, the noise of the data and of the class, the options.
  class.toml          only when --noise K asks for less noise than the recording has (see below): a
                      device class to give `fit multipos --device-class OUT/class.toml`.
  phone.csv           with --csv: the same samples as a phone logger writes them, header
                      `t_ms,ax_g,ay_g,az_g,gx_dps,gy_dps,gz_dps` (time in ms, accelerometer in g of
                      9.80665 m/s², gyro in deg/s), for `calbench import csv OUT/phone.csv --kind multipos
                      --time t_ms --time-unit ms --accel ax_g,ay_g,az_g --accel-unit g --gyro
                      gx_dps,gy_dps,gz_dps --gyro-unit deg/s ...`.

Static detection (this script's own): the gyro bias is the mean over the reference part of the
opening still interval (the first 48 s of the recording). Over a centred window of 51 samples
(0.5 s) two statistics are computed per sample: the mean of |ω − b|² over the window (gyro) and the
sum over the three axes of the accelerometer's sample variance in the window. Each threshold is
FACTOR (default 4, i.e. 2× in RMS) times the median of that statistic over the windows inside the
reference part (the median ignores the short disturbance near 5.5 s). A sample is still when both
statistics are below their thresholds; runs of still samples are eroded by a quarter second at each
end (the window's half-width: a window that only touches the motion can still pass) and those of
1 s or more are the static intervals. The opening interval is the static interval that holds
t = 40 s together with everything still before it.

--cut MIN,MAX   every static interval after the opening is shortened to a length drawn uniformly
                from [MIN, MAX] s (whole samples) by removing samples from its middle: its first
                half and its last half stay, so the transitions into and out of the pose are the
                recording's own; an interval already shorter is kept whole. Time is re-written
                uniform at 100 Hz from the first kept sample. The kept length is what this
                script's (conservative) detector calls still; the unit may be still a little longer
                at either end.
--opening S     keep only the last S s of the opening interval (the part next to the first turn); 0
                removes it, and the recording then starts at the first turn. Default: all of it.
--noise K       the white noise per sample becomes K × the Xsens MTi class's figure
                (bench/imu_classes/xsens-mti.toml: ARW 3 deg/√h and VRW 0.12 m/s/√h are densities
                of 0.05 deg/s/√Hz and 0.002 m/s²/√Hz, × √100 Hz: 0.5 deg/s = 8.73e-3 rad/s and
                0.02 m/s² per sample). Per axis, Gaussian white noise of σ = √((K·σ_class)² − σ_meas²)
                is added, σ_meas the axis's noise measured on the reference part (mean of the
                window variances; it includes the ADC's quantisation). The recording itself has
                about 0.43× the class on the accelerometer and 0.47× on the gyro. Noise cannot be
                removed: for a sensor where K·σ_class is below σ_meas nothing is added, and
                class.toml is written instead — the Xsens MTi class with that sensor's density set
                to (largest σ_meas of its axes) / K / √100 Hz, so that the data is K × that class
                (e.g. K = 0.3: the class is 3.3× noisier than the data). A sensor that could be
                re-noised keeps the Xsens figure, so in both sensors the data is K × class.toml's.
--seed N        the random generator's seed (the cut lengths are drawn first, pose by pose in
                time order, then the noise, sample by sample).

Distinct gravity directions: per kept pose the mean accelerometer vector (as written, after the
noise) normalised; greedy in time order a pose counts as a new direction unless it lies within 10° of
a direction already counted (the rule stated by calbench's fit, calibration/multipos/multipos_fit.cpp
"distinct gravity directions": u·d > cos 10° counts once).

Plain Python 3 (no numpy). Runs in a second or two.
"""
import argparse
import json
import math
import os
import random
import sys

ACC_OFFSET, ACC_SCALE = 32768.0, 0.0026808     # counts, m/s² per count
GYRO_OFFSET, GYRO_SCALE = 32768.0, 1.5979e-4    # counts, rad/s per count
RATE = 100.0                                    # Hz
G0 = 9.80665                                    # m/s² per g (the phone CSV's unit)
REF_S = 48.0                                    # reference part of the opening still interval
OPENING_PROBE_S = 40.0                          # the opening interval is the static interval holding this time
HALF = 25                                       # window half-width, samples (window 51 samples)
ERODE = 25                                      # samples removed at each end of a still run
MIN_STATIC_S = 1.0
DIR_TOL_DEG = 10.0
CLASS_TOML = "bench/imu_classes/xsens-mti.toml"
ARW_DEG_SQRT_H, VRW_M_S_SQRT_H = 3.0, 0.12      # that file's figures (checked against it at run time)


def read_triad(path):
    t, v = [], []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            s = line.split('%')[0].split('#')[0].split()
            if not s:
                continue
            if len(s) != 4:
                sys.exit(f"{path}:{n}: expected 4 columns, found {len(s)}")
            t.append(float(s[0]))
            v.append([float(x) for x in s[1:]])
    return t, v


def class_per_sample(src):
    """The Xsens MTi class's white noise per sample at 100 Hz: gyro rad/s, accel m/s²."""
    arw, vrw = ARW_DEG_SQRT_H, VRW_M_S_SQRT_H
    path = os.path.join(src, CLASS_TOML)
    if os.path.exists(path):  # keep to the file if it is there (the repository's own copy)
        for line in open(path):
            k = line.split('#')[0].split('=')
            if len(k) == 2 and k[0].strip() == "arw_deg_sqrt_h":
                arw = float(k[1])
            if len(k) == 2 and k[0].strip() == "vrw_m_s_sqrt_h":
                vrw = float(k[1])
    return (math.radians(arw / 60.0) * math.sqrt(RATE), vrw / 60.0 * math.sqrt(RATE), arw, vrw)


def window_stats(acc, gyr, bias):
    """Per sample: (mean |ω − b|² over the centred window, Σ over axes of the accel sample variance
    in the window); None where the window does not fit."""
    n = len(acc)
    cw = [0.0] * (n + 1)
    ca = [[0.0] * (n + 1) for _ in range(3)]
    ca2 = [[0.0] * (n + 1) for _ in range(3)]
    for i in range(n):
        w = gyr[i]
        cw[i + 1] = cw[i] + (w[0] - bias[0]) ** 2 + (w[1] - bias[1]) ** 2 + (w[2] - bias[2]) ** 2
        for a in range(3):
            x = acc[i][a]
            ca[a][i + 1] = ca[a][i] + x
            ca2[a][i + 1] = ca2[a][i] + x * x
    m = 2 * HALF + 1
    gs, av = [None] * n, [None] * n
    for i in range(HALF, n - HALF):
        lo, hi = i - HALF, i + HALF + 1
        gs[i] = (cw[hi] - cw[lo]) / m
        s = 0.0
        for a in range(3):
            su = ca[a][hi] - ca[a][lo]
            s += max(0.0, (ca2[a][hi] - ca2[a][lo] - su * su / m) / (m - 1))
        av[i] = s
    return gs, av


def median(v):
    v = sorted(v)
    k = len(v) // 2
    return v[k] if len(v) % 2 else 0.5 * (v[k - 1] + v[k])


def axis_noise(x, lo, hi):
    """Per axis: white noise per sample, the mean of the sample variances of 51-sample blocks in
    [lo, hi) (a slow drift does not count)."""
    out = []
    for a in range(3):
        vs = []
        for b in range(lo, hi - 2 * HALF, 2 * HALF + 1):
            blk = [x[i][a] for i in range(b, b + 2 * HALF + 1)]
            mu = sum(blk) / len(blk)
            vs.append(sum((y - mu) ** 2 for y in blk) / (len(blk) - 1))
        out.append(math.sqrt(sum(vs) / len(vs)))
    return out


def detect(acc, gyr, t, factor):
    n = len(t)
    ref_hi = next(i for i in range(n) if t[i] - t[0] >= REF_S)
    bias = [sum(gyr[i][a] for i in range(ref_hi)) / ref_hi for a in range(3)]
    gs, av = window_stats(acc, gyr, bias)
    thr_g = factor * median([gs[i] for i in range(HALF, ref_hi - HALF)])
    thr_a = factor * median([av[i] for i in range(HALF, ref_hi - HALF)])
    still = [gs[i] is not None and gs[i] <= thr_g and av[i] <= thr_a for i in range(n)]
    # The recording's first and last samples have no full window: still if their neighbour is.
    for i in range(HALF - 1, -1, -1):
        still[i] = still[i + 1]
    runs, i = [], 0
    while i < n:
        if still[i]:
            j = i
            while j < n and still[j]:
                j += 1
            lo = i if i == 0 else i + ERODE
            hi = j - ERODE
            if (hi - lo) / RATE >= MIN_STATIC_S:
                runs.append([lo, hi])  # samples [lo, hi)
            i = j
        else:
            i += 1
    probe = next(i for i in range(n) if t[i] - t[0] >= OPENING_PROBE_S)
    op = next((k for k, r in enumerate(runs) if r[0] <= probe < r[1]), None)
    if op is None:
        sys.exit("no still interval holds t = %g s: not the recording this script knows" % OPENING_PROBE_S)
    info = {"window_samples": 2 * HALF + 1, "threshold_factor": factor, "reference_s": [t[0], t[ref_hi - 1]],
            "gyro_threshold_rms_rad_s": math.sqrt(thr_g), "accel_threshold_sum_var_m2_s4": thr_a,
            "erode_samples": ERODE, "min_static_s": MIN_STATIC_S}
    return runs, op, ref_hi, info


def distinct_directions(means):
    dirs, first_of = [], []
    c = math.cos(math.radians(DIR_TOL_DEG))
    for k, f in enumerate(means):
        nf = math.sqrt(sum(x * x for x in f))
        u = [x / nf for x in f]
        if not any(sum(a * b for a, b in zip(u, d)) > c for d in dirs):
            dirs.append(u)
            first_of.append(k)
    return len(dirs), first_of


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="output folder (created; must not hold acc.txt already unless --force)")
    here = os.path.dirname(os.path.abspath(__file__))
    src = os.path.normpath(os.path.join(here, "..", ".."))
    ap.add_argument("--data", default=os.path.join(src, "..", "shared", "data", "imu_tk-xsens-multipos"),
                    help="folder with xsens_acc.mat and xsens_gyro.mat")
    ap.add_argument("--cut", help="MIN,MAX: shorten every pose after the opening to a length in [MIN, MAX] s")
    ap.add_argument("--opening", type=float, help="seconds of the opening still interval to keep (default all; 0 none)")
    ap.add_argument("--noise", type=float, help="white noise per sample = K × the Xsens MTi class's figure")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--csv", action="store_true", help="also write phone.csv (ms, g, deg/s)")
    ap.add_argument("--factor", type=float, default=4.0, help="detection threshold over the opening's median (default 4)")
    ap.add_argument("--force", action="store_true")
    a = ap.parse_args()

    cut = None
    if a.cut:
        try:
            cut = [float(x) for x in a.cut.split(",")]
            assert len(cut) == 2 and 0.5 <= cut[0] <= cut[1]
        except (ValueError, AssertionError):
            sys.exit("--cut: expected MIN,MAX seconds with 0.5 <= MIN <= MAX, got '%s'" % a.cut)
    if a.opening is not None and a.opening < 0:
        sys.exit("--opening: expected seconds >= 0")
    if a.noise is not None and not a.noise > 0:
        sys.exit("--noise: expected K > 0")
    if os.path.exists(os.path.join(a.out, "acc.txt")) and not a.force:
        sys.exit(f"{a.out} already holds acc.txt (--force to overwrite)")

    ta, ra = read_triad(os.path.join(a.data, "xsens_acc.mat"))
    tg, rg = read_triad(os.path.join(a.data, "xsens_gyro.mat"))
    if len(ta) != len(tg) or any(abs(x - y) > 1e-9 for x, y in zip(ta, tg)):
        sys.exit("the accelerometer and gyro files do not share their time stamps")
    acc = [[(c - ACC_OFFSET) * ACC_SCALE for c in r] for r in ra]
    gyr = [[(c - GYRO_OFFSET) * GYRO_SCALE for c in r] for r in rg]
    n = len(ta)

    runs, op, ref_hi, det = detect(acc, gyr, ta, a.factor)
    meas_a, meas_g = axis_noise(acc, 0, ref_hi), axis_noise(gyr, 0, ref_hi)
    rng = random.Random(a.seed)

    # --- Which samples stay. The opening: samples [0, runs[op][1]); its still part starts at 0.
    op_end = runs[op][1]
    keep = [True] * n
    first = 0
    if a.opening is not None:
        first = max(0, op_end - int(round(a.opening * RATE)))
    for i in range(first):
        keep[i] = False
    segments = []  # per static interval kept: list of (lo, hi) source sample ranges, flags
    for k, (lo, hi) in enumerate(runs):
        if k < op:
            if a.opening is not None:   # before the opening's still run (a disturbance inside the opening): dropped
                continue
            segments.append(([(lo, hi)], True, False))
            continue
        if k == op:
            lo2 = max(lo, first)
            if hi - lo2 >= MIN_STATIC_S * RATE:
                segments.append(([(lo2, hi)], True, False))
            continue
        if cut:
            L = int(round(rng.uniform(cut[0], cut[1]) * RATE))
            if hi - lo > L:
                h1 = L // 2
                mid0, mid1 = lo + h1, hi - (L - h1)
                for i in range(mid0, mid1):
                    keep[i] = False
                segments.append(([(lo, mid0), (mid1, hi)], False, True))
                continue
        segments.append(([(lo, hi)], False, False))

    # --- Output index of every kept source sample.
    out_idx, m = [None] * n, 0
    for i in range(n):
        if keep[i]:
            out_idx[i] = m
            m += 1
    t0 = round(ta[first], 2)  # the files write time to 0.01 s
    src_rows = [i for i in range(n) if keep[i]]
    A = [list(acc[i]) for i in src_rows]
    W = [list(gyr[i]) for i in src_rows]
    T = [t0 + j / RATE for j in range(m)]

    # --- Noise.
    cg, ca, arw, vrw = class_per_sample(src)
    noise = {"class": "Xsens MTi", "class_file": CLASS_TOML,
             "class_per_sample": {"gyro_rad_s": cg, "accel_m_s2": ca},
             "measured_per_sample": {"gyro_rad_s": meas_g, "accel_m_s2": meas_a},
             "measured_over_class": {"gyro": max(meas_g) / cg, "accel": max(meas_a) / ca}}
    data_g, data_a = list(meas_g), list(meas_a)
    class_file = None
    if a.noise is not None:
        K = a.noise
        noise["K"] = K
        add = {}
        cls_dens = {"arw_deg_sqrt_h": arw, "vrw_m_s_sqrt_h": vrw}
        for name, meas, csig, X in (("gyro", meas_g, cg, W), ("accel", meas_a, ca, A)):
            target = K * csig
            if target >= max(meas):
                sig = [math.sqrt(target * target - s * s) for s in meas]
                add[name] = {"mode": "added", "added_per_sample": sig, "total_per_sample": target}
            else:
                sig = None
                cls_sigma = max(meas) / K
                dens = cls_sigma / math.sqrt(RATE)
                if name == "gyro":
                    cls_dens["arw_deg_sqrt_h"] = math.degrees(dens) * 60.0
                else:
                    cls_dens["vrw_m_s_sqrt_h"] = dens * 60.0
                add[name] = {"mode": "class file", "class_per_sample": cls_sigma,
                             "total_per_sample": max(meas),
                             "why": "K × the Xsens class is below the recording's own noise: the data is kept "
                                    "and class.toml says 1/K × the data's noise"}
            if name == "gyro":
                data_g = [add[name]["total_per_sample"]] * 3 if sig else data_g
                sg = sig
            else:
                data_a = [add[name]["total_per_sample"]] * 3 if sig else data_a
                sa = sig
        for j in range(m):
            if sg:
                W[j] = [W[j][q] + rng.gauss(0.0, sg[q]) for q in range(3)]
            if sa:
                A[j] = [A[j][q] + rng.gauss(0.0, sa[q]) for q in range(3)]
        noise.update(add)
        if any(v["mode"] == "class file" for v in add.values()):
            class_file = "class.toml"
            noise["device_class_file"] = class_file
            noise["device_class_densities"] = cls_dens
    noise["data_per_sample"] = {"gyro_rad_s": data_g, "accel_m_s2": data_a}

    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "acc.txt"), "w") as fa, open(os.path.join(a.out, "gyro.txt"), "w") as fg:
        for j in range(m):
            fa.write("%.2f %.9g %.9g %.9g\n" % (T[j], A[j][0], A[j][1], A[j][2]))
            fg.write("%.2f %.9g %.9g %.9g\n" % (T[j], W[j][0], W[j][1], W[j][2]))
    if a.csv:
        with open(os.path.join(a.out, "phone.csv"), "w") as f:
            f.write("t_ms,ax_g,ay_g,az_g,gx_dps,gy_dps,gz_dps\n")
            for j in range(m):
                f.write("%.1f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n" % (
                    T[j] * 1e3, A[j][0] / G0, A[j][1] / G0, A[j][2] / G0,
                    math.degrees(W[j][0]), math.degrees(W[j][1]), math.degrees(W[j][2])))
    if class_file:
        d = noise["device_class_densities"]
        text = open(os.path.join(src, CLASS_TOML)).read()
        lines, head = [], True
        for line in text.splitlines():
            if head and line.startswith("#"):  # the file's own header: it describes the real class
                continue
            head = False
            key = line.split("=")[0].strip()
            if key == "name":
                line = 'name = "Xsens MTi, noisier variant (K=%g)"' % a.noise
            elif key == "aliases":
                line = "aliases = []"
            elif key == "arw_deg_sqrt_h":
                line = "arw_deg_sqrt_h = %.6g" % d["arw_deg_sqrt_h"]
            elif key == "vrw_m_s_sqrt_h":
                line = "vrw_m_s_sqrt_h = %.6g" % d["vrw_m_s_sqrt_h"]
            lines.append(line)
        hdr = ("# Written by bench/multipos/xsens_variants.py --noise %g: the Xsens MTi class (%s) with the\n"
               "# white noise of each sensor whose data could not be made K x the class set to 1/K x the data's\n"
               "# (arw %.6g deg/sqrt(h), vrw %.6g m/s/sqrt(h)), so that the data is K x this class.\n"
               % (a.noise, CLASS_TOML, d["arw_deg_sqrt_h"], d["vrw_m_s_sqrt_h"]))
        with open(os.path.join(a.out, class_file), "w") as f:
            f.write(hdr + "\n".join(lines) + "\n")

    # --- The poses kept, in output time, and their gravity directions.
    poses = []
    for parts, opening, was_cut in segments:
        idx = [out_idx[i] for lo, hi in parts for i in range(lo, hi) if out_idx[i] is not None]
        if len(idx) < MIN_STATIC_S * RATE:
            continue
        f = [sum(A[j][q] for j in idx) / len(idx) for q in range(3)]
        poses.append({"t0_s": T[idx[0]], "t1_s": T[idx[-1]] + 1 / RATE, "samples": len(idx),
                      "source_t0_s": ta[parts[0][0]], "source_t1_s": ta[parts[-1][1] - 1] + 1 / RATE,
                      "opening": opening, "cut": was_cut, "f_mean_m_s2": f,
                      "f_norm_m_s2": math.sqrt(sum(x * x for x in f))})
    nd, firsts = distinct_directions([p["f_mean_m_s2"] for p in poses])
    for k, p in enumerate(poses):
        p["new_direction"] = k in firsts
    data_sa = max(data_a)
    out = {
        "generator": "bench/multipos/xsens_variants.py",
        "source": {"data": os.path.abspath(a.data), "rows": n,
                   "conversion": {"accel": [ACC_OFFSET, ACC_SCALE], "gyro": [GYRO_OFFSET, GYRO_SCALE]}},
        "options": {"cut": cut, "opening_s": a.opening, "noise_k": a.noise, "seed": a.seed, "csv": a.csv,
                    "factor": a.factor},
        "rate_hz": RATE, "rows": m, "t0_s": T[0], "t1_s": T[-1],
        "detector": det,
        "detected_in_source": len(runs),
        "noise": noise,
        "pose_count": len(poses),
        "distinct_directions": nd,
        "direction_rule": "greedy in time order: a pose's mean accelerometer direction counts once when within "
                          "10 deg of a direction already counted (u.d > cos 10 deg)",
        "pose_mean_sigma_rms_m_s2": math.sqrt(sum(data_sa ** 2 / p["samples"] for p in poses) / max(1, len(poses))),
        "poses": poses,
    }
    with open(os.path.join(a.out, "poses.json"), "w") as f:
        json.dump(out, f, indent=1)
    print("%s: %d rows (%.1f s), %d poses (%d cut, %s opening), %d distinct gravity directions%s" % (
        a.out, m, m / RATE, len(poses), sum(p["cut"] for p in poses),
        "with" if any(p["opening"] for p in poses) else "no", nd,
        ", class.toml written" if class_file else ""))


if __name__ == "__main__":
    main()
