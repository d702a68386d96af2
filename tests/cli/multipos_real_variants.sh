#!/usr/bin/env bash
# Issue 55: multi-position calibration of real hand-turned units — the recording, not a guessed device
# class, decides what is still. Variants of IMU-TK's real Xsens recording made by
# bench/multipos/xsens_variants.py (its own static detection, no calbench code; truth-free poses.json:
# the poses kept and their number of distinct gravity directions), each fitted by `fit multipos`:
#   a  poses cut to 1–3 s, 10 s of the opening still interval kept, the data's own noise, "Xsens MTi"
#   b  poses cut to 1–3 s, no opening interval, re-noised to 1.5× the Xsens MTi class's white noise,
#      model "consumer MEMS" (ICM-42688-P: a class ~20× quieter on the gyro than this data)
#   c  poses cut to 1–3 s, no opening interval, 3× the Xsens class's noise, an unknown model ("Brand X",
#      no --device-class: the noise comes from the recording alone)
#   d  poses cut to 1–3 s, no opening interval, the data's own noise (it cannot be lowered) fitted with
#      the generator's class.toml (--device-class), whose white noise is 1/0.3 × the data's: the data is
#      0.3× the class, the class 3.3× too noisy
#   e  the whole recording as a phone logger's CSV (ms, g, deg/s) through import csv, "consumer MEMS"
# Each must fit (exit 0, --json and --out) and agree with the script and with the fit of the whole
# recording (import imu-tk, "Xsens MTi"):
#   - distinct gravity directions (multipos.distinct_directions) = the script's count ± 1: both count
#     greedily in time order with a 10° limit, so one pose the other tool splits, merges or leaves out,
#     or a pose mean a few mm/s² off near the 10° boundary of a counted direction, moves the count by 1;
#   - poses used ≥ 90 % of the script's poses (e: also within ±2 of the whole recording's imu-tk fit);
#   - calibrated |f| spread (g_spread_m_s2) ≤ the whole recording's + 2 × the RMS over the script's
#     poses of the white noise of a pose mean, σ/√n (σ the data's noise per sample, n the pose's samples);
#   - accelerometer scale factors (M diagonal) within 3σ (both fits' σ combined) + 500 ppm of the
#     whole recording's.
# Exit 77 when the shared data is absent. Runs in about 15 s.
set -euo pipefail
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
D="$SHARED/data/imu_tk-xsens-multipos"
[ -f "$D/xsens_acc.mat" ] || { echo "no $D: skipped"; exit 77; }
gen=(python3 "$SRC/bench/multipos/xsens_variants.py" --data "$D")
conv=(--acc-offset 32768 --acc-scale 0.0026808 --gyro-offset 32768 --gyro-scale 1.5979e-4 --gravity 9.81744)
# The whole recording, as tests/cli/multipos_fit.sh fits it: the reference the variants are held to.
"$CALBENCH" import imu-tk "$D/xsens_acc.mat" "$D/xsens_gyro.mat" --out "$tmp/full" "${conv[@]}" --model "Xsens MTi" --serial XS1 > /dev/null
"$CALBENCH" fit multipos "$tmp/full" --json > "$tmp/full.json"

"${gen[@]}" "$tmp/a" --cut 1,3 --opening 10 --seed 551
"${gen[@]}" "$tmp/b" --cut 1,3 --opening 0 --noise 1.5 --seed 552
"${gen[@]}" "$tmp/c" --cut 1,3 --opening 0 --noise 3 --seed 553
"${gen[@]}" "$tmp/d" --cut 1,3 --opening 0 --noise 0.3 --seed 554
"${gen[@]}" "$tmp/e" --csv --seed 555
[ -f "$tmp/d/class.toml" ] || { echo "d: the generator wrote no class.toml"; exit 1; }

# run V STEP CMD...: run a step of variant V, keep its exit code and messages (every variant is run
# and reported before the test fails).
run() {
  local v=$1 step=$2; shift 2
  set +e; "$@" > "$tmp/$v.$step.out" 2> "$tmp/$v.$step.err"; echo $? > "$tmp/$v.$step.rc"; set -e
}
imutk() {  # imutk V MODEL
  run "$1" import "$CALBENCH" import imu-tk "$tmp/$1/acc.txt" "$tmp/$1/gyro.txt" --out "$tmp/$1.rec" --model "$2" \
    --serial "XV-$1" --gravity 9.81744
}
imutk a "Xsens MTi"
imutk b "consumer MEMS"
imutk c "Brand X"
imutk d "Xsens MTi"
run e import "$CALBENCH" import csv "$tmp/e/phone.csv" --kind multipos --out "$tmp/e.rec" --time t_ms --time-unit ms \
  --accel ax_g,ay_g,az_g --accel-unit g --gyro gx_dps,gy_dps,gz_dps --gyro-unit deg/s --gravity 9.81744 \
  --model "consumer MEMS" --serial P1
for v in a b c d e; do
  extra=()
  [ "$v" = d ] && extra=(--device-class "$tmp/d/class.toml")
  run "$v" json "$CALBENCH" fit multipos "$tmp/$v.rec" --json "${extra[@]}"
  run "$v" out "$CALBENCH" fit multipos "$tmp/$v.rec" --out "$tmp/$v.coeffs.json" "${extra[@]}"
done

python3 - "$tmp" <<'PY'
import json, math, os, sys
tmp = sys.argv[1]
ref = json.load(open(os.path.join(tmp, "full.json")))
rm = ref["multipos"]
ref_used = sum(1 for s in rm["statics"] if s["used"])
what = {"a": "cut 1-3 s, 10 s opening, own noise, Xsens MTi",
        "b": "cut 1-3 s, no opening, 1.5x class noise, consumer MEMS",
        "c": "cut 1-3 s, no opening, 3x class noise, unknown model Brand X",
        "d": "cut 1-3 s, no opening, data 0.3x its class (--device-class class.toml)",
        "e": "whole recording, phone CSV (ms, g, deg/s), consumer MEMS"}
failed = []
for v in "abcde":
    P = json.load(open(os.path.join(tmp, v, "poses.json")))
    bad = []
    def step(name):
        rc = int(open(os.path.join(tmp, f"{v}.{name}.rc")).read())
        if rc != 0:
            err = open(os.path.join(tmp, f"{v}.{name}.err")).read().strip()
            bad.append(f"{name}: exit {rc}: {err}")
        return rc == 0
    line = f"{v} ({what[v]}): script {P['pose_count']} poses, {P['distinct_directions']} directions"
    if step("import") and step("json") & step("out"):
        j = json.load(open(os.path.join(tmp, f"{v}.json.out")))
        c = json.load(open(os.path.join(tmp, f"{v}.coeffs.json")))
        m = j["multipos"]
        used = sum(1 for s in m["statics"] if s["used"])
        need = math.ceil(0.9 * P["pose_count"])
        if used < need:
            bad.append(f"{used} poses used, at least {need} wanted (90 % of the script's {P['pose_count']})")
        if v == "e" and abs(used - ref_used) > 2:
            bad.append(f"{used} poses used, the imu-tk import of the same recording {ref_used}")
        dd = m.get("distinct_directions")
        if dd is None:
            bad.append("no multipos.distinct_directions in the --json output")
        elif abs(dd - P["distinct_directions"]) > 1:
            bad.append(f"{dd} distinct gravity directions, the script counts {P['distinct_directions']} (±1)")
        bound = rm["g_spread_m_s2"] + 2 * P["pose_mean_sigma_rms_m_s2"]
        if not m["g_spread_m_s2"] <= bound:
            bad.append("|f| spread %.2f mm/s² above %.2f mm/s²" % (1e3 * m["g_spread_m_s2"], 1e3 * bound))
        worst = 0.0
        for i in range(3):
            d = abs(j["accel"]["M"][i][i] - ref["accel"]["M"][i][i])
            lim = 3 * math.hypot(j["accel"]["sigma_M"][i][i], ref["accel"]["sigma_M"][i][i]) + 500e-6
            worst = max(worst, d / lim)
            if d > lim:
                bad.append("accel M[%d][%d] %.0f ppm from the whole recording's, limit %.0f ppm" % (i, i, 1e6 * d, 1e6 * lim))
        if c["accel"]["M"] != j["accel"]["M"]:
            bad.append("--json and --out disagree on accel M")
        line += ("; fit %d/%d poses used, %s directions, spread %.2f mm/s² (limit %.2f), M diagonal at %.2f of its limit"
                 % (used, len(m["statics"]), dd, 1e3 * m["g_spread_m_s2"], 1e3 * bound, worst))
    print(line)
    for b in bad:
        print("  FAIL " + b.replace("\n", "\n       "))
    if bad:
        failed.append(v)
if failed:
    print("multipos real variants failed: " + ", ".join(failed))
    sys.exit(1)
print("multipos real variants: ok")
PY
