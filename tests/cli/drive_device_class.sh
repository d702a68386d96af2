#!/usr/bin/env bash
# Device classes and the unit learned from the data (issue 34, items 1-2; docs/in-motion.md,
# "Device classes", "White noise measured on standstills"):
#  - an unknown device.model without --device-class is bad input (exit 2) listing the classes;
#  - --device-class FILE and NAME choose the class, RESULT.json records it;
#  - a drive simulated with the tactical class (KVH 1750) and fitted with the ADIS16488A class:
#    the white noise measured on its standstills is the KVH's (the simulator's level, used only to
#    score), 20x below the class, so the fit says so and uses it; fitted with its own class
#    (meta.json device.model) the class is kept;
#  - the real walk (meta.json "consumer MEMS"): the consumer class, its opening standstill
#    measured, the measured noise against the class reported.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
P="$SHARED/data/psins-vehicle-100s"
W="$SHARED/data/rtk-walk-135s"

# A recording whose model no class knows: exit 2, meta.json and device.model named, classes listed.
"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 3 --until 40 --out "$T/sim" >/dev/null
python3 - "$T/sim/meta.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1])); m["device"]["model"] = "Acme IMU-9000"; json.dump(m, open(sys.argv[1], "w"))
PY
set +e
"$CALBENCH" fit drive "$T/sim" --out "$T/r.json" 2>"$T/err"; rc=$?
set -e
[ "$rc" = 2 ] || { echo "unknown model: exit $rc, expected 2"; cat "$T/err"; exit 1; }
grep -q "meta.json: 'device.model': unknown IMU model 'Acme IMU-9000'" "$T/err"
for c in ADIS16488A ICM-42688-P ADIS16465-1 "KVH 1750"; do grep -q "$c" "$T/err" || { echo "class $c not listed"; cat "$T/err"; exit 1; }; done
grep -q -- "--device-class FILE" "$T/err"
[ ! -e "$T/r.json" ]
# A bad class file: exit 2 naming file, line and key.
sed 's/^vrw_m_s_sqrt_h = 0.029/vrw_m_s_sqrt_h = -1/' "$SRC/bench/imu_classes/adis16488a.toml" > "$T/bad.toml"
set +e
"$CALBENCH" fit drive "$T/sim" --device-class "$T/bad.toml" --out "$T/r.json" 2>"$T/err"; rc=$?
set -e
[ "$rc" = 2 ] && grep -q "bad.toml:25: 'accel.vrw_m_s_sqrt_h': out of range" "$T/err" || { echo "bad class file: exit $rc"; cat "$T/err"; exit 1; }
# --device-class FILE: accepted, recorded.
"$CALBENCH" fit drive "$T/sim" --device-class "$SRC/bench/imu_classes/adis16488a.toml" --out "$T/r.json" > "$T/s.txt"
grep -q "device class     ADIS16488A" "$T/s.txt"

# The tactical class simulated (its noise, drift, LSB; unit drawn from its spread), fitted with
# the ADIS16488A class and with its own.
"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --device-class "KVH 1750" --truth random --seed 4 \
  --until 60 --out "$T/kvh" >/dev/null
"$CALBENCH" fit drive "$T/kvh" --device-class ADIS16488A --out "$T/kvh_adis.json" > "$T/kvh_adis.txt"
grep -q "NOTE             the gyro white noise differs from the class by more than 2x" "$T/kvh_adis.txt"
grep -q "NOTE             the accel white noise differs from the class by more than 2x" "$T/kvh_adis.txt"
"$CALBENCH" fit drive "$T/kvh" --out "$T/kvh_own.json" > "$T/kvh_own.txt"
! grep -q "NOTE" "$T/kvh_own.txt"
python3 - "$T" "$SRC" <<'PY'
import json, sys, tomllib
d, src = sys.argv[1], sys.argv[2]
kvh = tomllib.load(open(src + "/bench/imu_classes/kvh1750.toml", "rb"))
meta = json.load(open(d + "/kvh/meta.json"))
assert meta["device"]["model"] == "KVH 1750", meta["device"]
a, o = json.load(open(d + "/kvh_adis.json")), json.load(open(d + "/kvh_own.json"))
assert a["device_class"]["name"] == "ADIS16488A" and a["device_class"]["chosen_by"] == "--device-class ADIS16488A"
assert o["device_class"]["name"] == "KVH 1750" and o["device_class"]["chosen_by"].startswith("meta.json device.model")
assert a["device_class"]["file"] == "bench/imu_classes/adis16488a.toml" and a["device_class"]["source"]["document"]
for r in (a, o):
    w = r["white_noise"]
    # The route's opening 20 s stop is found (the simulation starts standing), 1 s or more long.
    st = w["standstills"]
    assert st and st[0]["t_s"][0] < 0.5 and st[0]["t_s"][1] > 15, st
    # Measured = the simulated KVH level (truth side, for scoring only), within 10 %.
    for k, key, true in (("gyro_deg_sqrt_h", "gyro", kvh["gyro"]["arw_deg_sqrt_h"]),
                         ("accel_m_s_sqrt_h", "accel", kvh["accel"]["vrw_m_s_sqrt_h"])):
        for v in w["measured"][k]:
            assert abs(v / true - 1) < 0.10, (k, v, true)
# Against the ADIS class: ratio ~0.05 and ~2.4 -> measured used; against its own: class kept.
wa = a["white_noise"]
assert all(x < 0.5 for x in wa["ratio"]["gyro"]), wa["ratio"]
assert wa["used"]["gyro"]["source"].startswith("measured") and wa["used"]["accel"]["source"].startswith("measured"), wa["used"]
assert abs(wa["used"]["gyro"]["value"] / kvh["gyro"]["arw_deg_sqrt_h"] - 1) < 0.10
assert o["white_noise"]["used"]["gyro"]["source"].startswith("class"), o["white_noise"]["used"]
assert o["white_noise"]["used"]["gyro"]["value"] == kvh["gyro"]["arw_deg_sqrt_h"]
PY

# Real recordings. PSINS: model unknown -> exit 2 unless the class is named; no standstill there.
if [ -d "$P" ]; then
  set +e
  "$CALBENCH" fit drive "$P" --window 0:20 --out "$T/p.json" 2>"$T/err"; rc=$?
  set -e
  [ "$rc" = 2 ] && grep -q "unknown IMU model 'unknown low-cost MEMS IMU'" "$T/err" || { echo "PSINS: exit $rc"; cat "$T/err"; exit 1; }
  "$CALBENCH" fit drive "$P" --device-class ICM-42688-P --window 0:20 --out "$T/p.json" > "$T/p.txt"
  grep -q "white noise      no standstill found" "$T/p.txt"
  python3 -c "
import json; r = json.load(open('$T/p.json')); w = r['white_noise']
assert r['device_class']['name'] == 'ICM-42688-P' and w['measured'] is None and w['standstills'] == []
assert w['used']['gyro']['source'] == 'class (no standstill found)'"
fi
# The walk: 'consumer MEMS' -> ICM-42688-P; its opening standstill (from 1.2 s) measured.
if [ -d "$W" ]; then
  "$CALBENCH" fit drive "$W" --out "$T/w.json" > "$T/w.txt"
  grep -q "device class     ICM-42688-P (consumer MEMS; bench/imu_classes/icm42688p.toml, by meta.json device.model 'consumer MEMS')" "$T/w.txt"
  grep "white noise" "$T/w.txt"
  grep -q "white noise      measured on [1-9][0-9]* standstill(s): ARW xyz" "$T/w.txt"
  python3 -c "
import json; w = json.load(open('$T/w.json'))['white_noise']
s = w['standstills'][0]['t_s']
assert 1.0 < s[0] < 1.5 and s[1] - s[0] >= 1.0, s
assert all(0.05 < x < 20 for x in w['ratio']['gyro'] + w['ratio']['accel']), w['ratio']
print('walk: measured', w['measured'], 'class', w['class'], 'ratio', w['ratio'], 'standstills', [x['t_s'] for x in w['standstills']])"
fi
echo OK
