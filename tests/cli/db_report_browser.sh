#!/usr/bin/env bash
# calbench report SERIAL --html and report fleet --html: the pages open in headless Chromium and
# every embedded plot decodes (the page sets data-images="LOADED/TOTAL" on <body> after load).
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
export CALBENCH_DB="$T/r.db"
CHROMIUM=$(command -v chromium || command -v chromium-browser || true)
[ -n "$CHROMIUM" ] || fail "chromium not installed (scripts/setup installs it)"

python3 - <<'PY'
import json, random
r = random.Random(5)
def tri(bias, scale=1.0):
    return {"bias": [r.gauss(0, bias) for _ in range(3)],
            "M": [[r.gauss(0, (3e-3 if i == j else 3e-4) * scale) for j in range(3)] for i in range(3)],
            "sigma_bias": [bias / 100] * 3, "sigma_M": [[2e-5] * 3 for _ in range(3)]}
def coeffs(serial, g, a):
    return {"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": serial}, "gyro": g, "accel": a}
for i in range(12):
    g = tri(1e-3)
    if i == 11: g["M"][0][0] = 0.2   # a gross outlier
    json.dump(coeffs("U%02d" % i, g, tri(0.05)), open("u%02d.json" % i, "w"))
json.dump(coeffs("U00", tri(1e-3), tri(0.05)), open("u00b.json", "w"))
raw = {"gyro": tri(1e-3), "accel": tri(0.05)}
res = {"device": {"model": "ADIS16488A", "serial": "U00"}, "recording": {"path": "/drives/d<1>", "sha256": "cd" * 32},
       "coefficients": coeffs("U00", raw["gyro"], raw["accel"]), "correction": {"gyro": raw["gyro"], "accel": raw["accel"]},
       "mounting_rpy_deg": [0.1, -0.2, 0.3], "mounting_rpy_sigma_deg": [0.01, 0.01, 0.05],
       "consistency": {"pos": {"nis_mean": 1.1}},
       "qc": {"sets": [{"name": "bench", "cpe_m_at": {"0": 0, "60": 20.0, "300": 300.0, "600": 900.0}},
                       {"name": "bench+in-motion", "cpe_m_at": {"0": 0, "60": 2.0, "300": 12.0, "600": 40.0}}],
              "cpe_ratio": {"value": 22.5, "threshold": 10, "pass": True}}}
json.dump(res, open("result.json", "w"))
PY
"$CALBENCH" db init >/dev/null
for f in u*.json; do
  "$CALBENCH" db store-bench --coeffs "$f" --sha256 "$(printf 'a%.0s' {1..64})" --plan "factory <plan>" \
    --qc gyro_resid_rms=1e-5:1e-4:rad/s >/dev/null
done
"$CALBENCH" db approve 1 >/dev/null
"$CALBENCH" db import-inmotion result.json >/dev/null
"$CALBENCH" report U00 --html dev.html >/dev/null
"$CALBENCH" report fleet --html fleet.html >/dev/null
grep -q "U11" fleet.html || fail "outlier U11 not flagged in the fleet table"
grep -q "factory &lt;plan&gt;" dev.html || fail "text not escaped"

check() {  # check PAGE MIN_IMAGES
  "$CHROMIUM" --headless --no-sandbox --disable-gpu --no-first-run --disable-background-networking \
    --disable-component-update --disable-sync --user-data-dir="$T/profile" --virtual-time-budget=5000 \
    --dump-dom "file://$T/$1" > "$1.dom" 2> "$1.err" || { tail -5 "$1.err"; fail "chromium failed on $1"; }
  local n
  n=$(grep -o 'data-images="[0-9]*/[0-9]*"' "$1.dom" | head -1 | tr -dc '0-9/')
  [ -n "$n" ] || fail "$1: the page did not finish loading in the browser"
  [ "${n%/*}" = "${n#*/}" ] || fail "$1: only $n images decoded"
  [ "${n#*/}" -ge "$2" ] || fail "$1: $n images, expected at least $2"
  echo "$1: $n images decoded"
}
check dev.html 2       # coefficient history + circular position error
check fleet.html 4     # four distribution figures
grep -q "Circular position error" dev.html || grep -q 'alt="circular position error"' dev.html || fail "no CPE plot"
echo "db_report_browser: ok"
