#!/usr/bin/env python3
"""Side by side: calbench `fit multipos` and IMU-TK (Tedaldi, Pretto & Menegatti, ICRA 2014) on the
same multi-position recording, scored on held-out data by one scorer that knows neither estimator
(issue 37 item 3; docs/validation/peer-imu-tk.md is this script's output).

  bench/multipos/peer_imu_tk.py --calbench build/calbench --driver build-peer/imu_tk/build/imu_tk_driver \
      [--data ../shared/data/imu_tk-xsens-multipos] [--sim-seeds 101,102,103] [--variant-seed 561] \
      [--handheld-seeds 201,202,203] [--no-loro] [--peer 'Kyle-ak/imu_tk 7780270'] [--out docs/validation/peer-imu-tk.md]

The driver is built by scripts/peer-imu-tk. Both tools read the same two text files (IMU-TK's format,
raw counts); calbench through `import imu-tk` with a nominal conversion (counts offset 32768, IMU-TK's
own 1/6258 rad/s per count, 0.0027 m/s² per count), IMU-TK with its own example's settings. IMU-TK's
result (calibrated = T·K·(raw − b)) is converted to calbench's convention measured = (I + M)·true + b
on the SI values: I + M = S·K⁻¹·T⁻¹, b = S·(b_raw − offset), S the nominal scale.

Recordings of issue 55 (short hand-held poses), in SI: IMU-TK's xsens recording through
bench/multipos/xsens_variants.py (poses cut to 1–3 s, a 30-s opening still interval kept, its own noise,
1.5× and 3× the Xsens MTi class's), and `calbench simulate multipos` (poses of 1–3 s, a 30-s opening).
Both tools read the same SI files: calbench `import imu-tk` without a conversion, IMU-TK with bias 0
and unit scales as starting values (its static threshold is relative to its initial interval's
variance, so scale-free) and an initial static interval of the opening the file holds; its result is
converted with S = 1 and offset 0. No conversion back to counts (re-noised samples are no counts).

One segmentation for scoring: the static poses and rotations calbench finds on the whole recording
(the scorer needs pose means and rotation spans; both tools' coefficients are applied to the same ones).
Held-out metrics:
  * gravity magnitude, leave one pose out: each pose k is removed (calbench --exclude-pose k; IMU-TK:
    the pose's samples cut from its input, with 1 s on each side) and |‖A⁻¹(f̄_k − b)‖ − g| is scored
    on it. Poses inside IMU-TK's initial interval (50 s; 30 s on the issue-55 rows) are not left out
    (IMU-TK needs it).
  * gravity direction after a held-out rotation: IMU-TK cannot leave one rotation out, so both tools
    are fitted on each half of the recording (split at a long static pose near the middle, which both
    halves keep) and scored on the rotations of the other half: the gravity direction of the start pose,
    carried through the rotation by the corrected gyros, against the end pose's measured direction.
    calbench's leave-one-rotation-out (--exclude-rotation k) is listed as well.
"""
import argparse
import datetime
import json
import math
import os
import random
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hand_turn  # noqa: E402  (the turn both generators make)

OFFSET = 32768.0
ACC_SCALE = 0.0027          # m/s² per count (nominal)
GYRO_SCALE = 1.0 / 6258.0   # rad/s per count (IMU-TK's example)
G_XSENS = 9.81744


# ---------------------------------------------------------------- small linear algebra (3×3)
def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def mat_vec(a, v):
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def mat_inv(a):
    (p, q, r), (s, t, u), (v, w, x) = a
    det = p * (t * x - u * w) - q * (s * x - u * v) + r * (s * w - t * v)
    return [[(t * x - u * w) / det, (r * w - q * x) / det, (q * u - r * t) / det],
            [(u * v - s * x) / det, (p * x - r * v) / det, (r * s - p * u) / det],
            [(s * w - t * v) / det, (q * v - p * w) / det, (p * t - q * s) / det]]


def norm(v):
    return math.sqrt(sum(x * x for x in v))


def unit(v):
    n = norm(v)
    return [x / n for x in v]


class Triad:
    """A triad's correction true = A⁻¹(measured − b) in calbench's convention."""

    def __init__(self, M, b):
        self.Ainv = mat_inv([[(1.0 if i == j else 0.0) + M[i][j] for j in range(3)] for i in range(3)])
        self.b = b

    def __call__(self, v):
        return mat_vec(self.Ainv, [v[i] - self.b[i] for i in range(3)])


def from_calbench(coeffs_file):
    c = json.load(open(coeffs_file))
    return Triad(c["accel"]["M"], c["accel"]["bias"]), Triad(c["gyro"]["M"], c["gyro"]["bias"])


def from_imutk_triad(t, scale, offset=OFFSET):
    # true = T·K·(raw − b_raw), raw = ours/s + offset  ⇒  I + M = S·K⁻¹·T⁻¹, b = S·(b_raw − offset)
    # (files in SI: scale 1, offset 0)
    S = [[scale if i == j else 0.0 for j in range(3)] for i in range(3)]
    A = mat_mul(mat_mul(S, mat_inv(t["K"])), mat_inv(t["T"]))
    M = [[A[i][j] - (1.0 if i == j else 0.0) for j in range(3)] for i in range(3)]
    return Triad(M, [scale * (t["b"][i] - offset) for i in range(3)])


# ---------------------------------------------------------------- data
def read_imu_csv(folder):
    t, g, a = [], [], []
    with open(os.path.join(folder, "imu.csv")) as f:
        cols = None
        for line in f:
            if line.startswith("#"):
                continue
            if cols is None:
                cols = line.strip().split(",")
                continue
            v = [float(x) for x in line.split(",")]
            row = dict(zip(cols, v))
            t.append(row["t_s"])
            g.append([row["gx_rad_s"], row["gy_rad_s"], row["gz_rad_s"]])
            a.append([row["ax_m_s2"], row["ay_m_s2"], row["az_m_s2"]])
    return t, g, a


def qmul(p, q):
    a1, b1, c1, d1 = p
    a2, b2, c2, d2 = q
    return (a1 * a2 - b1 * b2 - c1 * c2 - d1 * d2, a1 * b2 + b1 * a2 + c1 * d2 - d1 * c2,
            a1 * c2 - b1 * d2 + c1 * a2 + d1 * b2, a1 * d2 + b1 * c2 - c1 * b2 + d1 * a2)


def qexp(phi):
    a = norm(phi)
    if a < 1e-12:
        return (1.0, 0.5 * phi[0], 0.5 * phi[1], 0.5 * phi[2])
    s = math.sin(a / 2) / a
    return (math.cos(a / 2), phi[0] * s, phi[1] * s, phi[2] * s)


def qrot_inv(q, v):
    """Rᵀ·v for the rotation R of unit quaternion q (body(end) → body(start))."""
    w, x, y, z = q
    R = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    return [sum(R[k][i] * v[k] for k in range(3)) for i in range(3)]


class Segmentation:
    def __init__(self, fit_json, t):
        m = json.load(open(fit_json))["multipos"]
        self.poses = []
        for s in m["statics"]:
            i0 = next(i for i, x in enumerate(t) if x >= s["t0_s"] - 1e-9)
            i1 = next(i for i, x in enumerate(t) if x >= s["t1_s"] - 1e-9) + 1
            self.poses.append((i0, i1, s["t0_s"], s["t1_s"]))
        self.rotations = [(r["from_pose"], r["to_pose"]) for r in m["rotations"]]


def pose_mean(a, i0, i1):
    n = i1 - i0
    return [sum(a[i][k] for i in range(i0, i1)) / n for k in range(3)]


def magnitude_error(acc, fbar, g):
    return abs(norm(acc(fbar)) - g)


def rotation_error_deg(acc, gyro, seg, t, g_data, fbars, k):
    p, q = seg.rotations[k]
    i1, i0 = seg.poses[p][1], seg.poses[q][0]
    quat = (1.0, 0.0, 0.0, 0.0)
    for j in range(i1, i0):
        dt = t[j] - t[j - 1]
        w = gyro(g_data[j])
        quat = qmul(quat, qexp([w[0] * dt, w[1] * dt, w[2] * dt]))
        n = math.sqrt(sum(x * x for x in quat))
        quat = tuple(x / n for x in quat)
    up0, up1 = unit(acc(fbars[p])), unit(acc(fbars[q]))
    pred = qrot_inv(quat, up0)
    return math.degrees(math.acos(max(-1.0, min(1.0, sum(pred[i] * up1[i] for i in range(3)) / norm(pred)))))


def rms(v):
    return math.sqrt(sum(x * x for x in v) / len(v)) if v else float("nan")


def median(v):
    s = sorted(v)
    n = len(s)
    return float("nan") if n == 0 else (s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2]))


# ---------------------------------------------------------------- tools
def run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}")
    return r


def write_rows(src, dst, keep):
    with open(src) as f, open(dst, "w") as o:
        for line in f:
            s = line.split()
            if s and keep(float(s[0])):
                o.write(line)


class Case:
    """One recording as a pair of IMU-TK text files. si=False: raw counts (calbench imports them with the
    nominal conversion, IMU-TK starts from its example's bias 32768 counts and gyro scale 1/6258);
    si=True: the files are in SI already (calbench imports them as they are, IMU-TK starts from bias 0
    and unit scales: the same starting point in these units, its static detection is scale-free)."""

    def __init__(self, a, work, acc_file, gyro_file, gravity, init_static, model, loro=True, si=False):
        self.a, self.work, self.acc_file, self.gyro_file = a, work, acc_file, gyro_file
        self.loro, self.si = loro, si
        self.g, self.init_static, self.model = gravity, init_static, model
        self.offset, self.acc_scale, self.gyro_scale = (0.0, 1.0, 1.0) if si else (OFFSET, ACC_SCALE, GYRO_SCALE)

    def calbench(self, acc_file, gyro_file, name, extra=()):
        rec = os.path.join(self.work, name)
        if not os.path.exists(os.path.join(rec, "meta.json")):
            conv = [] if self.si else ["--acc-offset", str(OFFSET), "--acc-scale", str(ACC_SCALE),
                                       "--gyro-offset", str(OFFSET), "--gyro-scale", repr(GYRO_SCALE)]
            run([self.a.calbench, "import", "imu-tk", acc_file, gyro_file, "--out", rec, *conv,
                 "--gravity", str(self.g), "--model", self.model, "--serial", "xsens-imu-tk"])
        out = os.path.join(self.work, name + "-" + "-".join(x.strip("-") for x in extra) + ".json")
        run([self.a.calbench, "fit", "multipos", rec, "--out", out, *extra])
        return out

    def imutk(self, acc_file, gyro_file, name, init_static=None, acc_only=False, verbose=False):
        out = os.path.join(self.work, name + "-imutk.json")
        cmd = [self.a.driver, acc_file, gyro_file, out, "--init-static", str(init_static or self.init_static),
               "--gravity", str(self.g), "--acc-bias-init", str(self.offset), "--gyro-scale-init", repr(self.gyro_scale)]
        if acc_only:
            cmd.append("--acc-only")
        if verbose:
            cmd.append("--verbose")
        r = subprocess.run(cmd, capture_output=True, text=True)
        if verbose:  # IMU-TK's own report: intervals extracted per threshold multiplier, the multiplier kept
            found = dict((int(m), int(n)) for n, m in
                         re.findall(r"extracted (\d+) intervals using threshold multiplier (\d+)", r.stdout))
            kept = re.findall(r"Better calibration obtained using threshold multiplier (\d+)", r.stdout)
            self.imutk_intervals = found.get(int(kept[-1])) if kept else None
        j = json.load(open(out)) if os.path.exists(out) else {"ok": False}
        if not j.get("ok"):
            return None
        acc = from_imutk_triad(j["acc"], self.acc_scale, self.offset)
        gyro = from_imutk_triad(j["gyro"], self.gyro_scale, self.offset) if "gyro" in j else None
        return acc, gyro

    def evaluate(self, loro=True):
        a = self.a
        full = self.calbench(self.acc_file, self.gyro_file, "full")
        rec = os.path.join(self.work, "full")
        t, gd, ad = read_imu_csv(rec)
        seg = Segmentation(full, t)
        fbars = [pose_mean(ad, p[0], p[1]) for p in seg.poses]
        res = {"poses": len(seg.poses), "rotations": len(seg.rotations), "duration": t[-1] - t[0]}
        cb = from_calbench(full)
        it = self.imutk(self.acc_file, self.gyro_file, "full", verbose=True)
        res["imutk_intervals"] = self.imutk_intervals
        if it is None:
            raise RuntimeError("IMU-TK found no calibration on the whole recording")
        for tool, (acc, gyro) in (("calbench", cb), ("IMU-TK", it)):
            res[tool] = {"in_mag": [magnitude_error(acc, f, self.g) for f in fbars],
                         "in_rot": [rotation_error_deg(acc, gyro, seg, t, gd, fbars, k) for k in range(len(seg.rotations))],
                         "coeffs": (acc, gyro)}
        # Leave one pose out (accelerometer).
        lo = [k for k, p in enumerate(seg.poses) if p[2] > t[0] + self.init_static + 1.0]
        res["lopo_poses"] = lo
        for tool in ("calbench", "IMU-TK"):
            res[tool]["lopo"] = []
        for k in lo:
            c = self.calbench(self.acc_file, self.gyro_file, "full", ("--exclude-pose", str(k)))
            res["calbench"]["lopo"].append(magnitude_error(from_calbench(c)[0], fbars[k], self.g))
            t0, t1 = seg.poses[k][2] - 1.0, seg.poses[k][3] + 1.0
            ca, cg = (os.path.join(self.work, f"cut{k}-{x}.txt") for x in ("acc", "gyro"))
            write_rows(self.acc_file, ca, lambda x: not (t0 <= x <= t1))
            write_rows(self.gyro_file, cg, lambda x: not (t0 <= x <= t1))
            r = self.imutk(ca, cg, f"cut{k}", acc_only=True)
            res["IMU-TK"]["lopo"].append(magnitude_error(r[0], fbars[k], self.g) if r else float("nan"))
        # Halves: split at the longest pose among the middle third of the poses (by count: each half then
        # has about as many poses as the other).
        n = len(seg.poses)
        mid = [(p[3] - p[2], k) for k, p in enumerate(seg.poses) if n / 3 <= k <= 2 * n / 3]
        ks = max(mid)[1]
        ts0, ts1 = seg.poses[ks][2], seg.poses[ks][3]
        res["split"] = (ks, ts0, ts1)
        fold_files = {}
        for name, keep in (("A", lambda x: x <= ts1), ("B", lambda x: x >= ts0)):
            fa, fg = (os.path.join(self.work, f"half{name}-{x}.txt") for x in ("acc", "gyro"))
            write_rows(self.acc_file, fa, keep)
            write_rows(self.gyro_file, fg, keep)
            fold_files[name] = (fa, fg)
        rot_a = [k for k, (p, q) in enumerate(seg.rotations) if q <= ks]
        rot_b = [k for k, (p, q) in enumerate(seg.rotations) if p >= ks]
        res["rot_folds"] = (len(rot_a), len(rot_b))
        for tool in ("calbench", "IMU-TK"):
            res[tool]["halves"] = []
            res[tool]["halves_mag"] = []
        for fit_on, score_on, poses_on in (("A", rot_b, range(ks + 1, len(seg.poses))), ("B", rot_a, range(0, ks))):
            fa, fg = fold_files[fit_on]
            try:
                c = from_calbench(self.calbench(fa, fg, "half" + fit_on))
            except RuntimeError as e:  # calbench refuses a half whose poses do not determine the coefficients
                lines = [x for x in str(e).splitlines() if "needed" in x or "spans only" in x or "no rotation" in x]
                res.setdefault("refused", []).append(f"calbench refused half {fit_on}: " + (lines[0].strip() if lines else "see its message"))
                c = None
            init = self.init_static if fit_on == "A" else (ts1 - ts0)
            i = self.imutk(fa, fg, "half" + fit_on, init_static=init)
            if i is None:  # calibrateAcc fails only when no threshold multiplier gives its 12 static intervals
                res.setdefault("refused", []).append(f"IMU-TK found no calibration on half {fit_on} (fewer than its "
                                                     "minimum of 12 static intervals at every threshold multiplier)")
            for tool, cal in (("calbench", c), ("IMU-TK", i)):
                if cal is None:
                    res[tool]["halves"] += [float("nan")] * len(score_on)
                    continue
                res[tool]["halves"] += [rotation_error_deg(cal[0], cal[1], seg, t, gd, fbars, k) for k in score_on]
                res[tool]["halves_mag"] += [magnitude_error(cal[0], fbars[k], self.g) for k in poses_on]
        if loro and self.loro:
            res["calbench"]["loro"] = []
            for k in range(len(seg.rotations)):
                c = from_calbench(self.calbench(self.acc_file, self.gyro_file, "full", ("--exclude-rotation", str(k))))
                res["calbench"]["loro"].append(rotation_error_deg(c[0], c[1], seg, t, gd, fbars, k))
        return res


# ---------------------------------------------------------------- simulation (independent of both tools)
def simulate(seed, folder):
    """A hand-turned unit: 50 s opening static, then 30 poses (3–6 s) reached by turns of 1.5–3 s about
    random body axes (a (1 − cos) rate profile), sampled at 100 Hz; errors measured = (I+M)·true + b
    with a raw-counts ADC (offset 32768 ± spread, nominal scale ± a few %), white noise at an Xsens
    MTi's densities. Written as IMU-TK text files in counts; the truth in calbench's convention on
    the nominal SI values. No code of either estimator is used."""
    rnd = random.Random(seed)
    rate, g = 100.0, 9.80665
    dt = 1 / rate
    truth = {}
    for name, sc, bias_si, skew in (("gyro", GYRO_SCALE, 0.02, 0.01), ("accel", ACC_SCALE, 0.3, 0.01)):
        M = [[(rnd.gauss(0, 0.03) if i == j else rnd.gauss(0, skew)) for j in range(3)] for i in range(3)]
        b = [rnd.gauss(0, bias_si) for _ in range(3)]
        truth[name] = {"M": M, "bias": b}
    sg, sa = 0.05 * math.pi / 180 * 10, 0.002 * 10  # per sample at 100 Hz
    C = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]  # body → level
    acc_rows, gyro_rows = [], []
    t = 0.0

    def emit(w):
        nonlocal t
        f = [C[2][i] * g for i in range(3)]  # up (level z) in body axes, times g
        for rows, true, name, s, sig in ((gyro_rows, w, "gyro", GYRO_SCALE, sg), (acc_rows, f, "accel", ACC_SCALE, sa)):
            e = truth[name]
            m = [sum(((1.0 if i == j else 0.0) + e["M"][i][j]) * true[j] for j in range(3)) + e["bias"][i] + rnd.gauss(0, sig)
                 for i in range(3)]
            rows.append("%.5f %.3f %.3f %.3f\n" % (t, *(OFFSET + m[i] / s for i in range(3))))
        t += dt

    def still(sec):
        for _ in range(int(sec * rate)):
            emit([0.0, 0.0, 0.0])

    still(50.0)
    for _ in range(30):
        ax = unit([rnd.gauss(0, 1) for _ in range(3)])
        theta = math.radians(rnd.uniform(60, 150)) * rnd.choice((-1, 1))
        T = rnd.uniform(1.5, 3.0)
        for r, d in hand_turn.turn_samples(theta, T, rate):
            C = mat_mul(C, hand_turn.rotation(ax, d))  # rotate the body about ax by d: C ← C·Rot(ax, d)
            emit([r * ax[0], r * ax[1], r * ax[2]])
        still(rnd.uniform(3.0, 6.0))
    os.makedirs(folder, exist_ok=True)
    open(os.path.join(folder, "acc.txt"), "w").writelines(acc_rows)
    open(os.path.join(folder, "gyro.txt"), "w").writelines(gyro_rows)
    json.dump(truth, open(os.path.join(folder, "truth.json"), "w"))
    return g


def truth_score(est_acc, est_gyro, truth, g):
    """Frame-invariant checks of a tool against the truth: errors of the gravity magnitude and of a
    rotation's action predicted from the coefficients, on a fixed set of test vectors."""
    ta = Triad(truth["accel"]["M"], truth["accel"]["bias"])
    tg = Triad(truth["gyro"]["M"], truth["gyro"]["bias"])
    worst_mag = 0.0
    rnd = random.Random(7)
    for _ in range(200):
        u = unit([rnd.gauss(0, 1) for _ in range(3)])
        true_f = [g * x for x in u]
        # measured from the truth: invert ta's correction
        A = mat_inv(ta.Ainv)
        meas = [sum(A[i][j] * true_f[j] for j in range(3)) + ta.b[i] for i in range(3)]
        worst_mag = max(worst_mag, abs(norm(est_acc(meas)) - g))
    return worst_mag


# ---------------------------------------------------------------- recordings of issue 55 (short poses)
XSENS_VARIANTS = (  # (title, xsens_variants.py options, calbench model)
    ("real xsens, poses cut to 1–3 s, 30-s opening", ["--cut", "1,3", "--opening", "30"], "Xsens MTi"),
    ("real xsens, cut 1–3 s, 30-s opening, 1.5× class noise", ["--cut", "1,3", "--opening", "30", "--noise", "1.5"],
     "Xsens MTi"),
    ("real xsens, cut 1–3 s, 30-s opening, 3× class noise, unknown model",
     ["--cut", "1,3", "--opening", "30", "--noise", "3"], "Brand X"),
)
HANDHELD_OPENING_S = 30.0


def xsens_variant(data, opts, seed, folder):
    """bench/multipos/xsens_variants.py (no code of either estimator): IMU-TK text files in SI and
    poses.json. Returns the opening still interval's length (the recording's first pose), IMU-TK's
    initial static interval."""
    run([sys.executable, os.path.join(os.path.dirname(os.path.abspath(__file__)), "xsens_variants.py"),
         "--data", data, *opts, "--seed", str(seed), folder])
    first = json.load(open(os.path.join(folder, "poses.json")))["poses"][0]
    if not first.get("opening"):
        raise RuntimeError(f"{folder}: no opening still interval (IMU-TK needs one)")
    return round(first["t1_s"] - first["t0_s"], 2)


def handheld(calbench, seed, folder):
    """`calbench simulate multipos`: hand-held poses of 1–3 s (its default), the class's noise, and an
    opening still interval of HANDHELD_OPENING_S (IMU-TK needs one). Its imu.csv (SI) is rewritten as
    IMU-TK text files; truth.json is in calbench's convention. Returns (model, gravity, truth)."""
    rec = os.path.join(folder, "rec")
    run([calbench, "simulate", "multipos", "--out", rec, "--seed", str(seed), "--opening-still", str(HANDHELD_OPENING_S)])
    t, g, a = read_imu_csv(rec)
    with open(os.path.join(folder, "acc.txt"), "w") as fa, open(os.path.join(folder, "gyro.txt"), "w") as fg:
        for i in range(len(t)):
            fa.write("%.5f %r %r %r\n" % (t[i], *a[i]))
            fg.write("%.5f %r %r %r\n" % (t[i], *g[i]))
    meta = json.load(open(os.path.join(rec, "meta.json")))
    return meta["device"]["model"], meta.get("gravity_m_s2", 9.80665), json.load(open(os.path.join(rec, "truth.json")))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--calbench", required=True)
    ap.add_argument("--driver", required=True, help="imu_tk_driver built by scripts/peer-imu-tk")
    ap.add_argument("--data", default=os.path.join(os.path.dirname(__file__), "../../../shared/data/imu_tk-xsens-multipos"))
    ap.add_argument("--sim-seeds", default="101,102,103")
    ap.add_argument("--variant-seed", type=int, default=561,
                    help="xsens_variants.py seed of the first variant (the others: +1, +2)")
    ap.add_argument("--handheld-seeds", default="201,202,203", help="`calbench simulate multipos` seeds")
    ap.add_argument("--peer", default="Kyle-ak/imu_tk")
    ap.add_argument("--out", help="write the markdown table here (default: stdout)")
    ap.add_argument("--no-loro", action="store_true", help="skip calbench's leave-one-rotation-out")
    a = ap.parse_args()
    for p in (a.calbench, a.driver):
        if not os.access(p, os.X_OK):
            sys.exit(f"peer_imu_tk.py: {p}: not an executable")
    lines = []
    rev = run(["git", "-C", os.path.dirname(os.path.abspath(__file__)), "rev-parse", "--short", "HEAD"]).stdout.strip()
    lines.append("# Side by side: calbench `fit multipos` and IMU-TK on multi-position recordings (issue 37 item 3)\n")
    lines.append("Generated by its command; not edited by hand and not rerun by `scripts/check-docs` (too long for CI);")
    lines.append("docs/multipos.md says how to read it.\n")
    lines.append(f"measured at {rev} ({datetime.date.today()}) · command: `bench/multipos/peer_imu_tk.py --calbench "
                 f"build/calbench --driver build-peer/imu_tk/build/imu_tk_driver --sim-seeds {a.sim_seeds} --variant-seed "
                 f"{a.variant_seed} --handheld-seeds {a.handheld_seeds}{' --no-loro' if a.no_loro else ''} --peer '{a.peer}'`\n")
    lines.append(f"Peer: IMU-TK ({a.peer}), its calibration core built unchanged with Debian's Ceres 2.1 by "
                 "`scripts/peer-imu-tk`, run by `tests/peer/imu_tk/driver.cpp` with the settings of its own "
                 "example (initial static 50 s, accelerometer bias 32768 counts, gyro scale 1/6258 rad/s per count). "
                 "calbench: `import imu-tk` with counts offset 32768, 0.0027 m/s² and 1/6258 rad/s per count, then "
                 "`fit multipos` with defaults. The scorer (this script) applies either tool's coefficients to the "
                 "same poses and rotations (calbench's segmentation of the whole recording).\n")
    lines.append("The rows of issue 55 (short hand-held poses; calbench's static detection learns the noise from the "
                 "recording), in SI: both tools read the same SI files, calbench through `import imu-tk` without a "
                 "conversion, IMU-TK with bias 0 and unit scales as its starting values (its static threshold is a "
                 "multiple of its initial interval's variance, so the unit does not matter) and its result converted "
                 "with scale 1 and offset 0; the files are not turned back into counts (re-noised samples are no counts). "
                 "IMU-TK's initial static interval is the opening the file holds: 30 s.\n")
    lines.append(f"- *real xsens, poses cut to 1–3 s, 30-s opening*: `bench/multipos/xsens_variants.py --cut 1,3 --opening 30 "
                 f"--seed {a.variant_seed}` on IMU-TK's recording: every pose after the opening shortened to 1–3 s "
                 "(samples removed from its middle, the turns the recording's own), the last 30 s of the opening kept, "
                 "the data's own noise (about 0.45× the Xsens MTi class's); calbench `--model \"Xsens MTi\"`.")
    lines.append(f"- *… 1.5× class noise*: the same with `--noise 1.5 --seed {a.variant_seed + 1}` (white noise re-added to "
                 "1.5× the Xsens MTi class's); calbench `--model \"Xsens MTi\"`.")
    lines.append(f"- *… 3× class noise, unknown model*: `--noise 3 --seed {a.variant_seed + 2}`, imported as `--model "
                 "\"Brand X\"` (no device class: calbench measures the noise on the recording and takes wide drift priors).")
    lines.append("- *`simulate multipos`, hand-held 1–3 s*: `calbench simulate multipos --seed S --opening-still 30`: one "
                 "ICM-42688-P unit (the class's spread, noise and bias drift), 24 poses held 1–3 s between hand turns, "
                 "the first pose held 30 s because IMU-TK needs an initial static interval (calbench does not; the "
                 "simulator's default has none). Its imu.csv is written out as IMU-TK text files; imported with the "
                 "unit's model (ICM-42688-P). The simulator is calbench's own (not its estimator); the truth and the "
                 "scorer are shared by both tools.\n")
    lines.append("IMU-TK keeps its own settings on every row: a static detector of 101-sample (1 s) variance windows, "
                 "intervals of at least 100 samples (100 taken from each), threshold multipliers 2–10 of its initial "
                 "interval's variance, the multiplier with the lowest residual kept; how many intervals that kept is "
                 "listed below (from its verbose output, the driver's `--verbose`). The in-sample figures score both "
                 "tools on the same poses, all of calbench's.\n")
    with tempfile.TemporaryDirectory() as work:
        cases = [("real: IMU-TK's xsens recording", Case(a, os.path.join(work, "xs"), os.path.join(a.data, "xsens_acc.mat"),
                                                         os.path.join(a.data, "xsens_gyro.mat"), G_XSENS, 50.0, "Xsens MTi"), None)]
        for s in [int(x) for x in a.sim_seeds.split(",") if x]:
            d = os.path.join(work, f"sim{s}")
            g = simulate(s, d)
            cases.append((f"simulated, seed {s}", Case(a, os.path.join(d, "w"), os.path.join(d, "acc.txt"),
                                                       os.path.join(d, "gyro.txt"), g, 50.0, "Xsens MTi", loro=False),
                          json.load(open(os.path.join(d, "truth.json")))))
        for k, (title, opts, model) in enumerate(XSENS_VARIANTS):
            d = os.path.join(work, f"var{k}")
            init = xsens_variant(a.data, opts, a.variant_seed + k, d)
            cases.append((title, Case(a, os.path.join(d, "w"), os.path.join(d, "acc.txt"), os.path.join(d, "gyro.txt"),
                                      G_XSENS, init, model, si=True), None))
        for s in [int(x) for x in a.handheld_seeds.split(",") if x]:
            d = os.path.join(work, f"hand{s}")
            model, g, truth = handheld(a.calbench, s, d)
            cases.append((f"`simulate multipos`, hand-held 1–3 s, seed {s}",
                          Case(a, os.path.join(d, "w"), os.path.join(d, "acc.txt"), os.path.join(d, "gyro.txt"),
                               g, HANDHELD_OPENING_S, model, si=True), truth))
        rows = []
        for title, case, truth in cases:
            os.makedirs(case.work, exist_ok=True)
            t_start = datetime.datetime.now()
            r = case.evaluate(loro=not a.no_loro)
            r["title"], r["truth"], r["init_static"] = title, truth, case.init_static
            rows.append(r)
            print(f"{title}: done ({(datetime.datetime.now() - t_start).total_seconds():.0f} s)", file=sys.stderr)
    mm = lambda v: 1e3 * v
    lines.append("## Held-out quality\n")
    lines.append("| recording | tool | poses / rotations | gravity magnitude, in-sample RMS (mm/s²) | leave-one-pose-out RMS (mm/s²) "
                 "| max (mm/s²) | gravity direction after a rotation, in-sample RMS (°) | held-out half: RMS (°) | median (°) "
                 "| max (°) | leave-one-rotation-out RMS (°) |")
    lines.append("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        for tool in ("calbench", "IMU-TK"):
            x = r[tool]
            lo = [v for v in x["lopo"] if v == v]
            hv = [v for v in x["halves"] if v == v]
            failed = len(x["lopo"]) - len(lo)
            lines.append(f"| {r['title']} | {tool} | {r['poses']} / {r['rotations']} | {mm(rms(x['in_mag'])):.2f} | "
                         f"{mm(rms(lo)):.2f}{f' ({failed} folds found no calibration)' if failed else ''} | "
                         f"{mm(max(lo)) if lo else float('nan'):.2f} | {rms(x['in_rot']):.3f} | {rms(hv):.3f} | {median(hv):.3f} | "
                         f"{max(hv) if hv else float('nan'):.3f} | "
                         f"{rms(x['loro']) if 'loro' in x else float('nan'):.3f} |".replace("nan", "—"))
    lines.append("")
    lines.append("In-sample gravity magnitude over the same poses (calbench's segmentation; IMU-TK's coefficients are scored "
                 "on all of them, including poses its own detector did not keep): calbench's RMS over IMU-TK's.\n")
    lines.append("| recording | poses scored | static intervals IMU-TK kept (its opening included) | calbench (mm/s²) "
                 "| IMU-TK (mm/s²) | ratio |")
    lines.append("|---|---:|---:|---:|---:|---:|")
    for r in rows:
        c, i = rms(r["calbench"]["in_mag"]), rms(r["IMU-TK"]["in_mag"])
        lines.append(f"| {r['title']} | {r['poses']} | {r['imutk_intervals'] if r['imutk_intervals'] is not None else '—'} "
                     f"| {mm(c):.2f} | {mm(i):.2f} | {c / i:.2f} |")
    lines.append("")
    for r in rows:
        for why in r.get("refused", []):
            lines.append(f"- {r['title']}: {why} (its held-out rotations count as not predicted: —)")
    lines.append("")
    lines.append("Left-out poses: every pose after IMU-TK's initial interval (50 s; 30 s on the issue-55 rows); halves split at the longest pose among the "
                 "middle third of the poses (both halves keep it; IMU-TK's initial interval for the second half is that pose).\n")
    sims = [r for r in rows if r["truth"]]
    if sims:
        lines.append("## Simulated recordings: against the truth\n")
        lines.append("Largest error of the calibrated gravity magnitude over 200 directions, the unit's true errors "
                     "applied (frame-invariant; IMU-TK and calbench fix the frame differently). calbench's σ: see "
                     "`tests/unit/calibration/multipos_fit_test.cpp` (coefficients within 3σ on simulated units).\n")
        lines.append("| recording | calbench (mm/s²) | IMU-TK (mm/s²) |")
        lines.append("|---|---:|---:|")
        for r in sims:
            lines.append(f"| {r['title']} | {mm(truth_score(r['calbench']['coeffs'][0], r['calbench']['coeffs'][1], r['truth'], 9.80665)):.2f} | "
                         f"{mm(truth_score(r['IMU-TK']['coeffs'][0], r['IMU-TK']['coeffs'][1], r['truth'], 9.80665)):.2f} |")
        lines.append("")
    text = "\n".join(lines) + "\n"
    if a.out:
        open(a.out, "w").write(text)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()
