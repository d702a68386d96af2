#!/usr/bin/env bash
# Acceptance: `calbench station run --emulated` on bench/plans/factory.toml completes, writes a complete
# recording and COEFFS.json, and the coefficients match the emulated unit's truth (EMULATED_TRUTH.json,
# written for this check only; the fit never reads it) within 5σ of their own uncertainty.
set -euo pipefail
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$CALBENCH" station run --plan "$SRC/bench/plans/factory.toml" --emulated --seed 7 --out "$tmp/out" --json \
  >"$tmp/summary.json" 2>"$tmp/log"
python3 - "$tmp" <<'PY'
import json, sys
d = sys.argv[1]
s = json.load(open(d + "/summary.json"))
assert s["ok"] and s["samples_lost"] == 0 and s["error_samples"] == 0, s["message"]
meta = json.load(open(d + "/out/recording/meta.json"))
assert meta.get("status", "complete") == "complete", meta
c = json.load(open(d + "/out/COEFFS.json"))
t = json.load(open(d + "/out/EMULATED_TRUTH.json"))
worst = 0
for tr in ("gyro", "accel"):
    for i in range(3):
        e = abs(c[tr]["bias"][i] - t[tr]["bias"][i]) / c[tr]["sigma_bias"][i]
        worst = max(worst, e)
        for j in range(3):
            e = abs(c[tr]["M"][i][j] - t[tr]["M"][i][j]) / c[tr]["sigma_M"][i][j]
            worst = max(worst, e)
assert worst < 5, "a coefficient is %.1f sigma from the truth" % worst
# Absolute sanity: gyro scale/skew within 30 ppm, accel bias within 3 mg.
for i in range(3):
    for j in range(3):
        assert abs(c["gyro"]["M"][i][j] - t["gyro"]["M"][i][j]) < 30e-6
    assert abs(c["accel"]["bias"][i] - t["accel"]["bias"][i]) < 3e-3 * 9.80665
print("ok: worst %.2f sigma, %d samples in %.1f s wall (%.0f s emulated)" % (worst, s["samples"], s["wall_s"], s["emulated_s"]))
PY
