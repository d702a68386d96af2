#!/usr/bin/env bash
# calbench db import-inmotion: a RESULT.json whose coefficients are the composition of a stored
# bench set and the in-motion correction becomes a combined set with that parent; unknown devices,
# mismatched serials and malformed files are refused (exit 2) with nothing written.
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
export CALBENCH_DB="$T/m.db"

python3 - <<'PY'
import json, random
r = random.Random(3)
def tri(bias):
    return {"bias": [r.gauss(0, bias) for _ in range(3)],
            "M": [[r.gauss(0, 3e-3 if i == j else 3e-4) for j in range(3)] for i in range(3)],
            "sigma_bias": [bias / 100] * 3, "sigma_M": [[2e-5] * 3 for _ in range(3)]}
def coeffs(serial, g, a):
    return {"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": serial}, "gyro": g, "accel": a}
bench = {"gyro": tri(1e-3), "accel": tri(0.05)}
corr = {"gyro": tri(1e-5), "accel": tri(1e-3)}
# Independent composition: M = (I+M1)(I+M2) - I, b = b1 + (I+M1) b2.
def compose(t1, t2):
    I = [[1.0 if i == j else 0.0 for j in range(3)] for i in range(3)]
    A = [[I[i][j] + t1["M"][i][j] for j in range(3)] for i in range(3)]
    B = [[I[i][j] + t2["M"][i][j] for j in range(3)] for i in range(3)]
    M = [[sum(A[i][k] * B[k][j] for k in range(3)) - I[i][j] for j in range(3)] for i in range(3)]
    b = [t1["bias"][i] + sum(A[i][k] * t2["bias"][k] for k in range(3)) for i in range(3)]
    return {"bias": b, "M": M, "sigma_bias": [1e-6] * 3, "sigma_M": [[3e-5] * 3 for _ in range(3)]}
total = {k: compose(bench[k], corr[k]) for k in ("gyro", "accel")}
json.dump(coeffs("IM1", bench["gyro"], bench["accel"]), open("bench.json", "w"))
res = {"device": {"model": "ADIS16488A", "serial": "IM1"},
       "recording": {"path": "/drives/d1", "sha256": "ab" * 32},
       "reference_system": "FOG INS",
       "coefficients": coeffs("IM1", total["gyro"], total["accel"]),
       "correction": {"gyro": corr["gyro"], "accel": corr["accel"]},
       "mounting_rpy_deg": {"value": [0.1, -0.2, 0.3], "sigma": [0.01, 0.01, 0.05]},
       "consistency": {"pos": {"nis_mean": 1.1}},
       "qc": {"from_s": 300, "horizon_s": 600, "sample": "out-of-sample (after the fit window)",
              "sets": [{"name": "input", "final_cpe_m": 900.0, "cpe_m_at": {"60": 20.0, "300": 300.0, "600": 900.0}},
                       {"name": "in-motion", "final_cpe_m": 40.0, "cpe_m_at": {"60": 2.0, "300": 12.0, "600": 40.0}}]}}
json.dump(res, open("result.json", "w"), indent=1)
bad = json.loads(json.dumps(res)); bad["device"]["serial"] = bad["coefficients"]["device"]["serial"] = "NOPE"; json.dump(bad, open("unknown.json", "w"))
bad = json.loads(json.dumps(res)); bad["coefficients"]["device"]["serial"] = "IM2"; json.dump(bad, open("mismatch.json", "w"))
bad = json.loads(json.dumps(res)); bad["mounting_rpy_deg"]["value"][0] = "0.1"; json.dump(bad, open("types.json", "w"))
bad = json.loads(json.dumps(res)); bad["coefficients"]["gyro"]["M"][0][0] += 1e-4; json.dump(bad, open("notcomposed.json", "w"))
text = open("result.json").read()
open("trunc.json", "w").write(text[: len(text) // 2])
open("nan.json", "w").write(text.replace("1.1", "NaN", 1))
PY
"$CALBENCH" db init >/dev/null
"$CALBENCH" db store-bench --coeffs bench.json --sha256 "$(printf 'a%.0s' {1..64})" --qc r=1:2 >/dev/null
counts() { sqlite3 "$CALBENCH_DB" "SELECT (SELECT COUNT(*) FROM coefficient_sets)||'/'||(SELECT COUNT(*) FROM inmotion_runs)||'/'||(SELECT COUNT(*) FROM qc_results)||'/'||(SELECT COUNT(*) FROM audit_log)"; }
before=$(counts)
for f in unknown mismatch types trunc nan; do
  set +e; "$CALBENCH" db import-inmotion $f.json 2> err.txt; rc=$?; set -e
  [ "$rc" = 2 ] || { cat err.txt; fail "$f.json: exit $rc"; }
  grep -q "$f.json" err.txt || { cat err.txt; fail "$f.json: message does not name the file"; }
done
grep -q "unknown device 'NOPE'" <("$CALBENCH" db import-inmotion unknown.json 2>&1 || true) || fail "unknown device message"
grep -q "does not match" <("$CALBENCH" db import-inmotion mismatch.json 2>&1 || true) || fail "mismatch message"
set +e; "$CALBENCH" db import-inmotion notcomposed.json --parent 1 2> err.txt; rc=$?; set -e
[ "$rc" = 2 ] && grep -q "not the composition of parent set 1" err.txt || { cat err.txt; fail "wrong parent accepted"; }
[ "$before" = "$(counts)" ] || fail "refused imports wrote something ($before -> $(counts))"
"$CALBENCH" db import-inmotion result.json --json > out.json
python3 - <<'PY' || fail "import result"
import json
o = json.load(open("out.json"))
assert o["source"] == "combined" and o["parent"] == 1 and o["version"] == 2, o
assert o["qc_metrics"] == 2, o   # final_cpe_m of the two sets (from_s, horizon_s are context)
PY
# The result's out-of-sample ΔS is checked against that of the set the fit started from; the
# input's is informative.
[ "$(sqlite3 "$CALBENCH_DB" "SELECT metric||'|'||IFNULL(threshold,'-')||'|'||pass||'|'||sample||'|'||unit FROM qc_results WHERE inmotion_run_id = 1 ORDER BY metric")" = \
  "$(printf 'sets.in-motion.final_cpe_m|900.0|1|out-of-sample|m\nsets.input.final_cpe_m|-|1|out-of-sample|m')" ] || fail "QC thresholds"
# Without a stored parent that composes (fit on raw data elsewhere): stored as in-motion, with a note.
"$CALBENCH" db import-inmotion notcomposed.json | grep -q "note: the fit started from a coefficient set that is not in the database" || fail "no-parent note"
[ "$(sqlite3 "$CALBENCH_DB" "SELECT source||','||IFNULL(parent_id,'-') FROM coefficient_sets WHERE id = 3")" = "in-motion,-" ] || fail "no-parent source"
# Issue 35 item 8: a result of `fit drive` says where its recording is (file://HOST/absolute/path)
# and carries the digest of all its files (docs/database.md "recording locations", computed here
# independently by tests/support/folder_digest.py); the import stores them (in the stored result)
# and `db history` (text and --json) and the device report show them, as for bench runs.
"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 2 --until 30 --out rec > /dev/null
"$CALBENCH" fit drive rec --window 0:20 --qc-horizon 5 --out fitted.json > /dev/null || fail "fit drive"
want_uri="file://$(hostname)$(cd rec && pwd -P)"
want_digest=$(python3 "$SRC/tests/support/folder_digest.py" rec)
[ ${#want_digest} = 64 ] || fail "independent digest"
python3 - "$want_uri" "$want_digest" <<'PY' || fail "RESULT.json recording uri/digest"
import json, os, sys
rec = json.load(open("fitted.json"))["recording"]
assert rec["uri"] == sys.argv[1], (rec["uri"], sys.argv[1])
host, path = rec["uri"][len("file://"):].split("/", 1)
assert host and "/" + path == os.path.realpath("rec"), rec["uri"]  # host present, path absolute
assert rec["digest_sha256"] == sys.argv[2], (rec["digest_sha256"], sys.argv[2])
PY
export CALBENCH_DB="$T/loc.db"
"$CALBENCH" db init > /dev/null
"$CALBENCH" db store-bench --coeffs rec/truth.json > /dev/null
"$CALBENCH" db import-inmotion fitted.json > /dev/null || fail "import of fit drive's result"
serial=$(python3 -c 'import json; print(json.load(open("rec/meta.json"))["device"]["serial"])')
"$CALBENCH" db history "$serial" > hist.txt
grep -q "^    recording $want_uri  SHA-256 of its files $want_digest\$" hist.txt || { cat hist.txt; fail "history: no in-motion recording line"; }
[ "$(grep -c "^    recording " hist.txt)" = 1 ] || { cat hist.txt; fail "history: a recording line for the bench set stored without a recording"; }
"$CALBENCH" db history "$serial" --json > hist.json
python3 - "$want_uri" "$want_digest" <<'PY' || fail "history --json"
import json, sys
h = [e for e in json.load(open("hist.json"))["history"] if e["entity"] == "inmotion_run"]
assert len(h) == 1 and h[0]["recording"]["uri"] == sys.argv[1] and h[0]["recording"]["digest_sha256"] == sys.argv[2], h
assert h[0]["recording"]["path"] == json.load(open("fitted.json"))["recording"]["path"], h
PY
"$CALBENCH" report "$serial" --html report.html > /dev/null
grep -q "$want_uri" report.html && grep -q "$want_digest" report.html || fail "device report: no recording URI or digest"
# A result written before them (no uri, no digest) still imports; nothing is invented for it.
python3 - <<'PY'
import json
j = json.load(open("fitted.json")); del j["recording"]["uri"]; del j["recording"]["digest_sha256"]
json.dump(j, open("older.json", "w"))
PY
"$CALBENCH" db import-inmotion older.json > /dev/null || fail "older result refused"
[ "$("$CALBENCH" db history "$serial" | grep -c "^    recording ")" = 1 ] || fail "older result shows a recording line"
echo "db_import_inmotion: ok"
