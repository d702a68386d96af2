#!/usr/bin/env bash
# Several MEMS units on one drive (issue 21, docs/recording-units.md):
#  - `simulate drive --units 4` writes units.json, the reference (and GNSS) once, one whole recording
#    per unit whose reference.csv is that same file; `--units 1` is today's one-unit recording;
#  - `fit drive DRIVE` fits all four against the reference parsed once: each unit's gyro drift,
#    accelerometer bias, scale and skew within 3σ of its own truth for ≥ 95 % of them (pooled) and
#    its mounting within 3σ; out-of-sample ΔS cut as for one unit; the same coefficients as the unit's
#    folder fitted alone; `db import-inmotion OUT` stores each against its device;
#  - bad input: a duplicate slot, a unit whose reference differs, --coeffs a file, --units with a
#    truth file → exit 2 naming it.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 5 --units 4 --out "$T/d" >/dev/null
[ -s "$T/d/units.json" ] && [ ! -e "$T/d/meta.json" ] && [ ! -e "$T/d/imu.csv" ] || fail "layout"
for k in 1 2 3 4; do
  for f in meta.json imu.csv reference.csv gnss.csv truth.json; do [ -s "$T/d/$k/$f" ] || fail "unit $k: no $f"; done
  cmp -s "$T/d/reference.csv" "$T/d/$k/reference.csv" && cmp -s "$T/d/gnss.csv" "$T/d/$k/gnss.csv" || fail "unit $k: another reference"
done
[ "$(stat -c %i "$T/d/reference.csv")" = "$(stat -c %i "$T/d/3/reference.csv")" ] || fail "reference.csv not one file"

"$CALBENCH" fit drive "$T/d" --out "$T/f" --window 0:150 > "$T/fit.txt" || { cat "$T/fit.txt"; fail "fit drive"; }
grep -q "4 of 4 units fitted against .*reference.csv (parsed once, 14062 epochs)" "$T/fit.txt" || { cat "$T/fit.txt"; fail "summary"; }
"$CALBENCH" fit drive "$T/d/3" --out "$T/alone3.json" --window 0:150 > /dev/null
python3 - "$T" <<'PY'
import json, sys
T = sys.argv[1]
u = json.load(open(T + "/f/units.json"))
assert u["format"] == "calbench-fit-units/1" and u["reference"]["rows"] == 14062, u["reference"]
assert u["reference"]["rows"] == sum(1 for l in open(T + "/d/reference.csv") if l[0].isdigit() or l[0] == "-")
ok = n = 0
for x in u["units"]:
    k = x["slot"]
    r = json.load(open(T + "/f/" + x["result"])); t = json.load(open("%s/d/%s/truth.json" % (T, k)))
    assert r["device"]["serial"] == t["device"]["serial"] == x["serial"]
    assert r["recording"]["sha256_reference"] == u["reference"]["sha256"]
    c = r["coefficients"]
    for tri in ("gyro", "accel"):
        for i in range(3):
            n += 1; ok += abs(c[tri]["bias"][i] - t[tri]["bias"][i]) <= 3 * c[tri]["sigma_bias"][i]
            for j in range(3):
                n += 1; ok += abs(c[tri]["M"][i][j] - t[tri]["M"][i][j]) <= 3 * c[tri]["sigma_M"][i][j]
    m = r["mounting_rpy_deg"]
    for i in range(3):
        assert abs(m["value"][i] - t["mounting"]["rpy_deg"][i]) <= 3 * m["sigma"][i] + 1e-9, (k, i, m, t["mounting"])
    q = {s["name"]: s["final_cpe_m"] for s in r["qc"]["sets"]}
    assert r["qc"]["sample"].startswith("out-of-sample") and q["in-motion"] < 0.05 * q["none"], (k, q)
    print("unit %s: ΔS %.0f m -> %.1f m" % (k, q["none"], q["in-motion"]))
assert ok >= 0.95 * n, (ok, n)
print("ok: %d of %d coefficients within 3 sigma" % (ok, n))
alone = json.load(open(T + "/alone3.json"))["coefficients"]
together = json.load(open(T + "/f/3/RESULT.json"))["coefficients"]
for tri in ("gyro", "accel"):
    assert alone[tri] == together[tri], "unit 3 fitted alone differs from the multi-unit fit"
PY
"$CALBENCH" db init --db "$T/s.db" > /dev/null
for k in 1 2 3 4; do "$CALBENCH" db store-bench --coeffs "$T/d/$k/truth.json" --db "$T/s.db" > /dev/null; done
"$CALBENCH" db import-inmotion "$T/f" --db "$T/s.db" > "$T/imp.txt"
[ "$(grep -c "^unit [1-4]: stored in-motion run" "$T/imp.txt")" = 4 ] || { cat "$T/imp.txt"; fail "import"; }
[ "$(sqlite3 "$T/s.db" "SELECT count(DISTINCT device_id) FROM inmotion_runs")" = 4 ] || fail "one in-motion run per device"

# A unit that fails in a rerun into the same OUT (issue 35 item 1): its slot keeps no RESULT.json of
# the earlier run (units.json says it failed); the units that fitted hold this run's result.
cp -a "$T/d" "$T/d2" && cp -a "$T/f" "$T/f2"
sed -i '60s/^[^,]*,/x,/' "$T/d2/2/imu.csv"
rc=0; "$CALBENCH" fit drive "$T/d2" --out "$T/f2" --window 0:60 --qc-horizon 30 > /dev/null 2> "$T/err.txt" || rc=$?
[ "$rc" = 2 ] && grep -q "unit 2: .*imu.csv" "$T/err.txt" || { cat "$T/err.txt"; fail "rerun with a bad unit: exit $rc"; }
[ ! -e "$T/f2/2/RESULT.json" ] || fail "a failed unit's slot keeps the earlier run's RESULT.json"
python3 - "$T/f2" <<'PY' || fail "rerun: units.json and results"
import json, sys
u = {x["slot"]: x for x in json.load(open(sys.argv[1] + "/units.json"))["units"]}
assert not u["2"]["ok"] and "result" not in u["2"], u["2"]
for k in "134":
    assert u[k]["ok"], u[k]
    assert json.load(open(sys.argv[1] + "/" + u[k]["result"]))["window_s"][1] <= 60, k  # this run's, not the earlier
PY
# Every unit fails in a rerun: no result and no units.json of the earlier run stays.
for k in 1 3 4; do sed -i '60s/^[^,]*,/x,/' "$T/d2/$k/imu.csv"; done
rc=0; "$CALBENCH" fit drive "$T/d2" --out "$T/f2" --window 0:60 > /dev/null 2> "$T/err.txt" || rc=$?
[ "$rc" = 2 ] || { cat "$T/err.txt"; fail "rerun with every unit bad: exit $rc"; }
[ ! -e "$T/f2/units.json" ] && [ -z "$(find "$T/f2" -name RESULT.json)" ] || fail "every unit failed: earlier results stay"

# simulate drive --units: each unit is complete with the drive's shared reference and GNSS in it.
for k in 2 3 4; do
  python3 -c 'import json,sys; assert json.load(open(sys.argv[1]))["status"] == "complete"' "$T/d/$k/meta.json" || fail "unit $k not complete"
  [ "$(stat -c %i "$T/d/gnss.csv")" = "$(stat -c %i "$T/d/$k/gnss.csv")" ] || fail "unit $k: gnss.csv not the shared file"
done

# One unit: today's recording (no units.json).
"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 5 --units 1 --until 20 --out "$T/one" >/dev/null
[ -s "$T/one/meta.json" ] && [ ! -e "$T/one/units.json" ] || fail "--units 1 is not a one-unit recording"

expect2() {  # expect2 WHAT PATTERN COMMAND...
  local what=$1 pat=$2; shift 2
  local rc=0
  "$@" > /dev/null 2> "$T/err.txt" || rc=$?
  [ "$rc" = 2 ] && grep -q -- "$pat" "$T/err.txt" || { cat "$T/err.txt"; fail "$what: exit $rc"; }
}
expect2 "--coeffs a file" "several units: --coeffs names a folder" "$CALBENCH" fit drive "$T/d" --out "$T/g" --coeffs "$T/d/1/truth.json"
expect2 "--units with a truth file" "several units need --truth random" "$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth "$T/d/1/truth.json" --units 2 --out "$T/x"
sed -i 's/"slot": "2"/"slot": "1"/' "$T/d/units.json"
expect2 "duplicate slot" "units.json: 'units\[1\].slot': duplicate slot '1'" "$CALBENCH" fit drive "$T/d" --out "$T/g"
sed -i 's/"slot": "1",\(.*\)/"slot": "1",\1/' "$T/d/units.json"
python3 - "$T/d/units.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1])); j["units"][1]["slot"] = "2"; json.dump(j, open(sys.argv[1], "w"))
PY
rm "$T/d/2/reference.csv"; head -n 100 "$T/d/reference.csv" > "$T/d/2/reference.csv"
expect2 "another reference" "2/reference.csv: missing or not the drive's reference.csv" "$CALBENCH" fit drive "$T/d" --out "$T/g"
echo "PASS"
