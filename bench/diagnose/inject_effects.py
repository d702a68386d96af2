#!/usr/bin/env python3
"""Add one effect outside calbench's own simulator to a clean recording (issue 36).

An independent generator: it shares no code with calbench's C++ effect hooks. It reads a recording
folder (docs: /work/shared/spec/recording-format.md, "calbench-recording/1"), computes the effect
only from what the recording's reference says the IMU experienced (bench: reference.csv rates and
specific forces; drive: reference.csv velocity) and the recording clock, adds it to the IMU
outputs, and writes a new folder (atomically: a temporary folder renamed at the end). Every other
file is copied unchanged; `injected.json` records the effect and its parameters.

Effects (amplitudes at the edges in °/h, °/s, mg, °C; SI inside):
  warmup      bias following a warm-up temperature T(t) = T0 + dT·(1 − exp(−t/tau)):
              b = k·(T − T0), k = --change / dT. The curve is also written to temp_c (replacing a
              column that is there), because a unit that warms reports it. Gyro (°/h) or accel (mg).
  deadband    gyro rate dead band: a true rate |w| < --width (°/s) on the axis gives no output
              (the effect is −w there, 0 outside). Bench only (needs the true rates).
  memory      gyro bias with memory of the last rotation direction: +m after the last rotation of
              the axis (|w| > --threshold °/s) was positive, −m after a negative one, 0 before any.
              Bench only.
  saturation  gyro output clipped at ±--limit (°/s; default 97 % of the largest true rate about
              the axis in the reference, i.e. the top of the plan's rates). Bench only.
  speed       bias proportional to the reference speed |v| (drive only): b = k·|v|, k in °/h per
              m/s (gyro) or mg per m/s (accel).
  shift       a turn-on bias shift: a constant added to one axis (°/h gyro, mg accel).

Rates and increments: imu.csv may carry rates (gx_rad_s, ...) or increments over the interval
ending at t_s (dax_rad, ..., dvx_m_s, ...). Increments are turned into mean rates over their
interval (the first interval is 1/imu_rate_hz), the effect added, and turned back.

Bad input (missing column or file, a non-number, NaN/inf, time going backwards, an effect the
recording kind cannot carry) is refused with file, line and field named, exit status 2.

Usage: inject_effects.py IN_DIR OUT_DIR EFFECT [options]   (inject_effects.py -h for the options)
"""
import argparse
import bisect
import csv
import json
import math
import os
import shutil
import sys
import tempfile

DEG = math.pi / 180.0
DPH = DEG / 3600.0          # °/h in rad/s
MG = 9.80665e-3             # mg in m/s²
AXES = "xyz"


class InputError(Exception):
    pass


def fail(msg):
    print(f"inject_effects.py: {msg}", file=sys.stderr)
    sys.exit(2)


def read_csv(path, required):
    """Header, columns by name (floats) for the names in `required` plus all numeric columns,
    comment lines kept for the header. Checks numbers and monotonic t_s."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: missing file")
    comments, header, rows = [], None, []
    with open(path, newline="") as fh:
        for lineno, line in enumerate(fh, 1):
            s = line.rstrip("\r\n")
            if not s.strip():
                continue
            if s.startswith("#"):
                if header is None:
                    comments.append(s)
                continue
            fields = next(csv.reader([s]))
            if header is None:
                header = [f.strip() for f in fields]
                for r in required:
                    if r not in header:
                        raise InputError(f"{path}:{lineno}: missing required column '{r}'")
                continue
            if len(fields) != len(header):
                raise InputError(f"{path}:{lineno}: {len(fields)} fields, header has {len(header)}")
            rows.append((lineno, fields))
    if header is None:
        raise InputError(f"{path}: no header line")
    cols = {h: [] for h in header}
    for lineno, fields in rows:
        for h, f in zip(header, fields):
            try:
                v = float(f)
            except ValueError:
                raise InputError(f"{path}:{lineno}: column '{h}': not a number: '{f}'")
            if not math.isfinite(v):
                raise InputError(f"{path}:{lineno}: column '{h}': not finite: '{f}'")
            cols[h].append(v)
    t = cols.get("t_s", [])
    for i in range(1, len(t)):
        if t[i] < t[i - 1]:
            raise InputError(f"{path}:{rows[i][0]}: column 't_s': time goes backwards ({t[i]!r} after {t[i-1]!r})")
    if not rows:
        raise InputError(f"{path}: no data rows")
    return comments, header, cols


def interp(tq, t, y):
    """Linear interpolation of y(t) at the sorted times tq (held at the ends)."""
    out, n = [], len(t)
    j = 0
    for q in tq:
        while j + 1 < n and t[j + 1] <= q:
            j += 1
        if j + 1 >= n or q <= t[0]:
            out.append(y[min(j, n - 1)] if q > t[0] else y[0])
        else:
            a = (q - t[j]) / (t[j + 1] - t[j]) if t[j + 1] > t[j] else 0.0
            out.append(y[j] + a * (y[j + 1] - y[j]))
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("input", help="clean recording folder (meta.json, imu.csv, reference.csv and/or gnss.csv)")
    p.add_argument("output", help="folder to write (must not exist unless --force)")
    p.add_argument("effect", choices=["warmup", "deadband", "memory", "saturation", "speed", "shift"])
    p.add_argument("--sensor", choices=["gyro", "accel"], default="gyro", help="triad (default gyro; deadband, memory, saturation: gyro only)")
    p.add_argument("--axis", choices=list(AXES) + ["all"], default="z", help="IMU axis, or all three (default z)")
    p.add_argument("--change", type=float, default=None,
                   help="warmup: bias change over the warm-up, °/h gyro (default 20) or mg accel (default 1)")
    p.add_argument("--dT", type=float, default=10.0, help="warmup: temperature rise, °C (default 10)")
    p.add_argument("--T0", type=float, default=25.0, help="warmup: start temperature, °C (default 25)")
    p.add_argument("--tau", type=float, default=None,
                   help="warmup: time constant, s (default: a third of the recording, so ~95 %% of dT is reached)")
    p.add_argument("--width", type=float, default=0.01, help="deadband: half-width, °/s (default 0.01)")
    p.add_argument("--memory", type=float, default=30.0, help="memory: bias after a rotation, °/h (default 30)")
    p.add_argument("--threshold", type=float, default=1.0, help="memory: rate that counts as a rotation, °/s (default 1)")
    p.add_argument("--limit", type=float, default=None,
                   help="saturation: clip level, °/s (default 97 %% of the largest true rate about the axis)")
    p.add_argument("--k", type=float, default=None,
                   help="speed: °/h per m/s (gyro, default 1) or mg per m/s (accel, default 0.1)")
    p.add_argument("--bias", type=float, default=None,
                   help="shift: the bias step, °/h (gyro, default 30) or mg (accel, default 3)")
    p.add_argument("--force", action="store_true", help="replace an existing output folder")
    a = p.parse_args()
    try:
        run(a)
    except InputError as e:
        fail(str(e))


def run(a):
    meta_path = os.path.join(a.input, "meta.json")
    if not os.path.isfile(meta_path):
        raise InputError(f"{meta_path}: missing file")
    try:
        with open(meta_path) as fh:
            meta = json.load(fh)
    except json.JSONDecodeError as e:
        raise InputError(f"{meta_path}:{e.lineno}: not JSON: {e.msg}")
    kind = meta.get("kind")
    if kind not in ("bench", "drive"):
        raise InputError(f"{meta_path}: field 'kind': '{kind}' (this injector takes bench or drive)")
    rate = meta.get("imu_rate_hz")
    if not isinstance(rate, (int, float)) or not rate > 0:
        raise InputError(f"{meta_path}: field 'imu_rate_hz': missing or not positive")
    if a.effect in ("deadband", "memory", "saturation") and a.sensor != "gyro":
        raise InputError(f"--sensor accel: the {a.effect} effect is a gyro effect")
    if a.effect in ("deadband", "memory", "saturation") and kind != "bench":
        raise InputError(f"{meta_path}: kind '{kind}': {a.effect} needs the true rates of a bench reference.csv")
    if a.effect == "speed" and kind != "drive":
        raise InputError(f"{meta_path}: kind '{kind}': speed needs a drive reference (velocity)")
    if os.path.exists(a.output) and not a.force:
        raise InputError(f"{a.output}: exists (use --force to replace it)")

    imu_path = os.path.join(a.input, "imu.csv")
    comments, header, imu = read_csv(imu_path, ["t_s"])
    rate_cols = [f"g{c}_rad_s" for c in AXES] + [f"a{c}_m_s2" for c in AXES]
    inc_cols = [f"da{c}_rad" for c in AXES] + [f"dv{c}_m_s" for c in AXES]
    if all(c in header for c in rate_cols):
        increments, cols = False, rate_cols
    elif all(c in header for c in inc_cols):
        increments, cols = True, inc_cols
    else:
        missing = [c for c in rate_cols if c not in header]
        raise InputError(f"{imu_path}:1: missing column '{missing[0]}' (neither rates nor increments complete)")
    t = imu["t_s"]
    n = len(t)
    dt = [1.0 / rate] + [t[i] - t[i - 1] for i in range(1, n)]
    if increments and any(d <= 0 for d in dt[1:]):
        i = next(i for i in range(1, n) if dt[i] <= 0)
        raise InputError(f"{imu_path}: column 't_s': repeated time at data row {i + 1} (increments need a positive interval)")
    # Mean rates / specific forces over each sample interval.
    out = {}
    for k, c in enumerate(cols):
        out[k] = [v / d for v, d in zip(imu[c], dt)] if increments else list(imu[c])
    base = 0 if a.sensor == "gyro" else 3
    axes = [0, 1, 2] if a.axis == "all" else [AXES.index(a.axis)]
    ref_path = os.path.join(a.input, "reference.csv")
    params = {"effect": a.effect, "sensor": a.sensor, "axis": a.axis}

    def true_rates():
        _, _, ref = read_csv(ref_path, ["t_s", "wx_rad_s", "wy_rad_s", "wz_rad_s"])
        # The interval's mean: the reference at the interval's midpoint.
        tm = [ti - 0.5 * d for ti, d in zip(t, dt)]
        return {ax: interp(tm, ref["t_s"], ref[f"w{AXES[ax]}_rad_s"]) for ax in axes}

    temp = None
    if a.effect == "warmup":
        change = a.change if a.change is not None else (20.0 if a.sensor == "gyro" else 1.0)
        unit = DPH if a.sensor == "gyro" else MG
        span = t[-1] - t[0]
        tau = a.tau if a.tau is not None else max(span / 3.0, 1e-9)
        if tau <= 0 or a.dT == 0:
            raise InputError("--tau must be positive and --dT non-zero")
        temp = [a.T0 + a.dT * (1.0 - math.exp(-(ti - t[0]) / tau)) for ti in t]
        k = change * unit / a.dT
        for ax in axes:
            out[base + ax] = [v + k * (T - a.T0) for v, T in zip(out[base + ax], temp)]
        params.update(change=change, change_unit="deg/h" if a.sensor == "gyro" else "mg", dT_c=a.dT, T0_c=a.T0, tau_s=tau)
    elif a.effect == "deadband":
        w = true_rates()
        d = a.width * DEG
        for ax in axes:
            out[ax] = [v - wi if abs(wi) < d else v for v, wi in zip(out[ax], w[ax])]
        params.update(width_dps=a.width)
    elif a.effect == "memory":
        w = true_rates()
        m, th = a.memory * DPH, a.threshold * DEG
        for ax in axes:
            state, col = 0.0, out[ax]
            for i, wi in enumerate(w[ax]):
                if wi > th:
                    state = 1.0
                elif wi < -th:
                    state = -1.0
                col[i] += state * m
        params.update(memory_dph=a.memory, threshold_dps=a.threshold)
    elif a.effect == "saturation":
        w = true_rates()
        limits = {}
        for ax in axes:
            lim = a.limit * DEG if a.limit is not None else 0.97 * max(abs(x) for x in w[ax])
            if lim <= 0:
                raise InputError("--limit must be positive")
            out[ax] = [max(-lim, min(lim, v)) for v in out[ax]]
            limits[AXES[ax]] = lim / DEG
        params.update(limit_dps=limits)
    elif a.effect == "speed":
        _, _, ref = read_csv(ref_path, ["t_s", "vn_m_s", "ve_m_s", "vd_m_s"])
        speed = [math.sqrt(x * x + y * y + z * z) for x, y, z in zip(ref["vn_m_s"], ref["ve_m_s"], ref["vd_m_s"])]
        tm = [ti - 0.5 * d for ti, d in zip(t, dt)]
        s = interp(tm, ref["t_s"], speed)
        k = a.k if a.k is not None else (1.0 if a.sensor == "gyro" else 0.1)
        unit = DPH if a.sensor == "gyro" else MG
        for ax in axes:
            out[base + ax] = [v + k * unit * si for v, si in zip(out[base + ax], s)]
        params.update(k=k, k_unit="deg/h per m/s" if a.sensor == "gyro" else "mg per m/s")
    elif a.effect == "shift":
        b = a.bias if a.bias is not None else (30.0 if a.sensor == "gyro" else 3.0)
        unit = DPH if a.sensor == "gyro" else MG
        for ax in axes:
            out[base + ax] = [v + b * unit for v in out[base + ax]]
        params.update(bias=b, bias_unit="deg/h" if a.sensor == "gyro" else "mg")

    for k, c in enumerate(cols):
        imu[c] = [v * d for v, d in zip(out[k], dt)] if increments else out[k]
    if temp is not None:
        if "temp_c" not in header:
            header = header + ["temp_c"]
        imu["temp_c"] = temp

    parent = os.path.dirname(os.path.abspath(a.output))
    tmp = tempfile.mkdtemp(prefix=".inject.", dir=parent)
    try:
        for name in os.listdir(a.input):
            src = os.path.join(a.input, name)
            if name != "imu.csv" and os.path.isfile(src):
                shutil.copy2(src, os.path.join(tmp, name))
        with open(os.path.join(tmp, "imu.csv"), "w", newline="") as fh:
            for c in comments:
                fh.write(c + "\n")
            fh.write(",".join(header) + "\n")
            data = [imu[h] for h in header]
            for row in zip(*data):
                fh.write(",".join(repr(v) for v in row) + "\n")
        with open(os.path.join(tmp, "injected.json"), "w") as fh:
            json.dump({"generator": "bench/diagnose/inject_effects.py", "source": os.path.abspath(a.input),
                       **params}, fh, indent=2)
            fh.write("\n")
        if os.path.exists(a.output):
            shutil.rmtree(a.output)
        os.rename(tmp, a.output)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


if __name__ == "__main__":
    main()
