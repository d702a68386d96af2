#!/usr/bin/env bash
# calbench provision against the emulated ADIS16488A: only approved sets; --export; serial and
# PROD_ID mismatch refused and recorded; the registers written equal the approved set quantised as
# the device stores them (computed here independently), read back equal, event recorded.
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
export CALBENCH_DB="$T/p.db"
python3 - <<'PY'
import json, random
r = random.Random(9)
def tri(bias):
    return {"bias": [r.gauss(0, bias) for _ in range(3)],
            "M": [[r.gauss(0, 3e-3 if i == j else 3e-4) for j in range(3)] for i in range(3)],
            "sigma_bias": [bias / 1000] * 3, "sigma_M": [[2e-5] * 3 for _ in range(3)]}
json.dump({"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": "4660"},
           "gyro": tri(1e-3), "accel": tri(0.05)}, open("c.json", "w"))
PY
"$CALBENCH" db init >/dev/null
"$CALBENCH" db store-bench --coeffs c.json --sha256 "$(printf 'a%.0s' {1..64})" --qc r=1:2 >/dev/null
set +e; "$CALBENCH" provision 4660 --export x.json 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] && grep -q "no approved coefficient set: its newest, set 1, is draft (calbench db approve 1)" err.txt || { cat err.txt; fail "draft set provisioned"; }
"$CALBENCH" db approve 1 --operator qc-anna >/dev/null
"$CALBENCH" provision 4660 --export x.json | grep -q "exported" || fail "export"
python3 -c 'import json; assert json.load(open("x.json")) == json.load(open("c.json"))' || fail "exported set differs"
# Wrong unit: SERIAL_NUM 0x1234 = 4660 expected; 4661 refused; wrong PROD_ID refused.
set +e; "$CALBENCH" provision 4660 --to-device emu://4661 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] && grep -q "SERIAL_NUM is 4661, not 4660" err.txt || { cat err.txt; fail "serial mismatch"; }
set +e; "$CALBENCH" provision 4660 --to-device "emu://4660?prod_id=0x4060" 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] && grep -q "PROD_ID 0x4060" err.txt || { cat err.txt; fail "PROD_ID mismatch"; }
[ "$(sqlite3 "$CALBENCH_DB" "SELECT status FROM coefficient_sets WHERE id = 1")" = approved ] || fail "refusal changed status"
set +e; "$CALBENCH" provision 4660 --to-device "emu://4660?flash_fails=1" --json > fl.json 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] || { cat err.txt; fail "flash failure not reported"; }
"$CALBENCH" provision 4660 --to-device emu://4660 --json > prov.json
python3 - <<'PY' || fail "registers"
import json, math
c = json.load(open("c.json")); p = json.load(open("prov.json"))
assert p["ok"] and p["serial_num"] == 4660 and p["prod_id"] == 0x4068, p
assert p["written"] == p["read_back"], (p["written"], p["read_back"])
assert p["flash_count_after"] == p["flash_count_before"] + 1, p
# Device model (docs/devices.md): output = (1 + SCALE/2^15)·raw + BIAS·LSB; cancel (1+m)·true + b.
lsb = {"gyro": 0.02 / 65536 * math.pi / 180, "accel": 0.8e-3 * 9.80665 / 65536}
def rnd(x): return int(math.floor(x + 0.5)) if x >= 0 else -int(math.floor(-x + 0.5))
for t in ("gyro", "accel"):
    for i in range(3):
        m, b = c[t]["M"][i][i], c[t]["bias"][i]
        s = rnd((1 / (1 + m) - 1) * 32768)
        B = rnd(-(1 + s / 32768) * b / lsb[t])
        assert p["written"][t + "_scale"][i] == s, (t, i, s, p["written"])
        assert p["written"][t + "_bias"][i] == B, (t, i, B, p["written"])
PY
[ "$(sqlite3 "$CALBENCH_DB" "SELECT status FROM coefficient_sets WHERE id = 1")" = provisioned ] || fail "status not provisioned"
ev=$(sqlite3 "$CALBENCH_DB" "SELECT group_concat(kind||':'||ok, ' ') FROM provisioning_events ORDER BY id")
[ "$ev" = "export:1 device:0 device:0 device:0 device:1" ] || fail "events: $ev"
sqlite3 "$CALBENCH_DB" "SELECT readback_json FROM provisioning_events WHERE ok = 1 AND kind = 'device'" | grep -q '"read_back"' || fail "readback not recorded"
# Re-provisioning (issue 17): after a first provisioning the default set is the one the unit holds;
# it can be written again (a replaced or re-flashed unit) without --set, and approving it again
# is not a refusal.
"$CALBENCH" provision 4660 --to-device emu://4660 --json > again.json || fail "re-provisioning without --set"
python3 -c 'import json; p = json.load(open("again.json")); assert p["ok"] and p["set"] == 1, p' || fail "re-provisioned set"
"$CALBENCH" db approve 1 --operator qc-anna | grep -q "already provisioned" || fail "approving a provisioned set"
echo "db_provision: ok"
