#!/usr/bin/env bash
# Verdicts that look at the fit (issue 35 item 5): a bench fit carries its χ²/dof per triad axis and
# the mean residual of every step ("fit_quality" of COEFFS.json); db store-bench stores them with
# the set; db approve refuses a set whose fit does not fit (naming the triad, the axis, the step kind)
# and the device report shows the residuals (tables and SVG plots with units). An in-motion set whose
# mean NIS per degree of freedom leaves its band is refused naming the observation. Malformed
# thresholds and fit_quality keys exit 2 naming the file and key.
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
export CALBENCH_DB="$T/v.db" CALBENCH_STATION=line-1
expect() {  # expect RC PATTERN CMD...: exit RC and stderr matches PATTERN
  local want=$1 pat=$2; shift 2
  set +e; "$@" > out.txt 2> err.txt; local rc=$?; set -e
  [ "$rc" = "$want" ] || { cat out.txt err.txt; fail "exit $rc (expected $want): $*"; }
  grep -q -- "$pat" err.txt || { cat err.txt; fail "message does not name '$pat': $*"; }
}

# Two units on the factory plan: a good one, and one with a g-sensitivity the model lacks (33 °/h/g).
"$CALBENCH" simulate bench --plan "$SRC/bench/plans/factory.toml" --truth random --seed 1 --serial GOOD1 --out good >/dev/null
"$CALBENCH" simulate bench --plan "$SRC/bench/plans/factory.toml" --truth random --seed 1 --serial GSENS1 --out gsens \
  --inject g_sensitivity:axis=x,f=y,value=1.6e-4 >/dev/null
"$CALBENCH" fit bench good --out good.json > good.txt
"$CALBENCH" fit bench gsens --out gsens.json > gsens.txt
# The text output says what db approve will say of the fit (issue 35 sign-off): one warning per
# failing figure, then that approval will refuse it; nothing of the kind for the good unit.
grep -q "^warning: bench fit gyro x: χ²/dof = .* exceeds 3 " gsens.txt || { cat gsens.txt; fail "fit bench: no χ²/dof warning"; }
grep -q "^warning: bench fit gyro: largest systematic residual of the static positions" gsens.txt \
  || { cat gsens.txt; fail "fit bench: no systematic residual warning"; }
grep -q "^warning: db approve will refuse this set (. fit-quality figure(s) outside the built-in defaults of device class ADIS16488A" gsens.txt \
  || { cat gsens.txt; fail "fit bench: does not say db approve will refuse"; }
[ "$(grep -c '^warning: bench fit' gsens.txt)" -ge 2 ] || fail "fit bench: one warning per failing figure"
grep -q "warning" good.txt && { cat good.txt; fail "fit bench warns about a good fit"; }
python3 - <<'PY' || fail "fit_quality in COEFFS.json"
import json
for f in ("good.json", "gsens.json"):
    q = json.load(open(f))["fit_quality"]
    assert len(q["chi2_per_dof"]["gyro"]) == 3 and len(q["chi2_per_dof"]["accel"]) == 3, q["chi2_per_dof"]
    kinds = {s["kind"] for s in q["steps"]}
    assert kinds == {"static", "rate"}, kinds
    assert set(q["largest_systematic"]) == {"static", "rate"}, q["largest_systematic"]
g = json.load(open("good.json"))["fit_quality"]; b = json.load(open("gsens.json"))["fit_quality"]
assert max(g["chi2_per_dof"]["gyro"]) < 1.5, g["chi2_per_dof"]
assert b["chi2_per_dof"]["gyro"][0] > 10, b["chi2_per_dof"]   # the unmodelled effect is on gyro x
PY
"$CALBENCH" db init >/dev/null
for u in good gsens; do
  "$CALBENCH" db store-bench --coeffs $u.json --recording $u --plan factory --qc samples_lost=0:0 --operator op-ben >/dev/null
done
# The figures are stored with the set (the payload keeps them as the fit wrote them).
"$CALBENCH" db export 2 --out stored.json >/dev/null
python3 -c '
import json; a = json.load(open("gsens.json"))["fit_quality"]; b = json.load(open("stored.json"))["fit_quality"]
assert a == b, "fit_quality changed in the store"' || fail "fit_quality not stored with the set"
"$CALBENCH" db approve 1 --operator qc-anna > /dev/null || fail "the good bench set was refused"
expect 1 "bench fit gyro x: χ²/dof = .* exceeds 3" "$CALBENCH" db approve 2 --operator qc-anna
grep -q "bench fit gyro: largest systematic residual of the static positions = .* °/h (step .*) exceeds 60 °/h" err.txt \
  || { cat err.txt; fail "systematic residual of the static positions not named"; }
grep -q "accel" err.txt && { cat err.txt; fail "the accelerometer fits: it must not be named"; }
[ "$(sqlite3 "$CALBENCH_DB" "SELECT status FROM coefficient_sets WHERE id = 2")" = draft ] || fail "refused set changed"
"$CALBENCH" db approve 2 --operator qc-anna --json > appr.json 2>/dev/null || true
python3 -c '
import json; j = json.load(open("appr.json")); assert not j["approved"]
assert any("χ²/dof" in r for r in j["reasons"]), j' || fail "--json reasons"
# The limits are the thresholds file's: tighter ones refuse the good set, naming the triad and kind.
echo '{"bench": {"max_chi2_dof": {"accel": 0.5}, "max_systematic_residual": {"rate": {"gyro_dph": 1}}}}' > tight.json
"$CALBENCH" db store-bench --coeffs good.json --recording good --plan factory --qc samples_lost=0:0 --operator op-ben \
  --started 2026-01-01T00:00:00Z >/dev/null
expect 1 "bench fit accel .: χ²/dof = .* exceeds 0.5" "$CALBENCH" db approve 3 --operator qc-anna --thresholds tight.json
grep -q "bench fit gyro: largest systematic residual of the rate steps = .* exceeds 1 °/h" err.txt || { cat err.txt; fail "rate-step limit"; }
grep -q "static positions" err.txt && { cat err.txt; fail "the static limit was not tightened"; }
# A bench set without the figures: approved by default, refused when the file requires them.
python3 -c '
import json; c = json.load(open("good.json")); del c["fit_quality"]; c["device"]["serial"] = "OLD1"; json.dump(c, open("old.json", "w"))'
"$CALBENCH" db store-bench --coeffs old.json --plan factory --qc samples_lost=0:0 --sha256 "$(printf 'a%.0s' {1..64})" --operator op-ben >/dev/null
echo '{"bench": {"require_fit_quality": true}}' > req.json
expect 1 "bench fit quality not recorded" "$CALBENCH" db approve 4 --operator qc-anna --thresholds req.json
"$CALBENCH" db approve 4 --operator qc-anna > /dev/null || fail "a set without figures refused by default"

# The report: χ²/dof and systematic residuals in tables, the step residuals as SVG with units.
"$CALBENCH" report GSENS1 --html g.html > /dev/null
python3 - <<'PY' || fail "report residuals"
import re
h = open("g.html").read()
assert 'id="chi2-2"' in h and 'id="systematic-2"' in h, "tables missing"
chi = h[h.index('id="chi2-2"'):]; chi = chi[:chi.index("</table>")]
assert chi.count('class="fail"') == 1, chi          # gyro x only
for cls, unit in (("residual-gyro", "mean residual [°/h]"), ("residual-accel", "mean residual [mg]")):
    m = re.search(r'<svg[^>]*class="%s".*?</svg>' % cls, h, re.S)
    assert m, cls
    svg = m.group(0)
    assert unit in svg and "plan step" in svg, (cls, svg[:300])
    assert len(re.findall(r'<polyline[^>]*data-curve="(gyro|accel) [xyz]"', svg)) == 3, cls
assert 'data-verdict="FAIL"' in h and "χ²/dof" in h[h.index('id="verdict-reasons"'):], "verdict"
PY

# In-motion: NIS per observation in the verdict. A fit with its consistency, and the same result
# with the position innovations 20× larger than the filter predicted (what a too-small assumed
# noise gives): refused naming position; a band in the thresholds file refuses the first.
"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 5 --serial 4242 --out rec >/dev/null
"$CALBENCH" fit drive rec --window 0:150 --out r.json > fit.txt
python3 - <<'PY'
import json
r = json.load(open("r.json"))
c = r["consistency"]["position"]
c["mean_nis"] = 20 * c["expected_nis"]
json.dump(r, open("bad_nis.json", "w"))
PY
python3 "$SRC/tests/support/make_coeffs.py" 4242 3 > b4242.json   # the unit must be known to the store
"$CALBENCH" db store-bench --coeffs b4242.json --sha256 "$(printf 'd%.0s' {1..64})" --operator op-ben >/dev/null
"$CALBENCH" db import-inmotion r.json > /dev/null
"$CALBENCH" db import-inmotion bad_nis.json > /dev/null
n1=$(sqlite3 "$CALBENCH_DB" "SELECT MAX(id) - 1 FROM coefficient_sets"); n2=$((n1 + 1))
expect 1 "in-motion NIS position: mean 60 over .* epochs = 20 per degree of freedom, outside the band 0.1 – 2" \
  "$CALBENCH" db approve $n2 --operator qc-anna
python3 -c '
import json; p = json.load(open("r.json"))["consistency"]["position"]
print(json.dumps({"inmotion": {"mean_nis_per_dof": {"position": [p["mean_nis"] / p["expected_nis"] * 1.5, 100]}}}))' > band.json
expect 1 "in-motion NIS position: .* outside the band" "$CALBENCH" db approve $n1 --operator qc-anna --thresholds band.json
grep -q "NIS velocity" err.txt && { cat err.txt; fail "velocity named though its band is the default"; }
# A run whose filter ended with the IMU's noise scaled away (issue 53: the real walk before, ×3.5e5
# with NIS 3.01) is refused whatever its NIS, and the device report says FAILED beside the NIS.
python3 - <<'PY'
import json
r = json.load(open("r.json"))
r["adaptive_noise"] = {"enabled": True, "option": "auto", "scale_max": 6.44e5, "scale_end": 3.5e5, "increases": 6}
json.dump(r, open("scaled.json", "w"))
PY
"$CALBENCH" db import-inmotion scaled.json > /dev/null
n3=$(sqlite3 "$CALBENCH_DB" "SELECT MAX(id) FROM coefficient_sets")
expect 1 "in-motion filter: the navigation noise variance was scaled ×3.5e+05 at the end of the fit (limit 10)" \
  "$CALBENCH" db approve $n3 --operator qc-anna
grep -q "NIS position" err.txt && { cat err.txt; fail "the scaled run's NIS named: it was consistent"; }
"$CALBENCH" report 4242 --html scaled.html > /dev/null
python3 - <<'PY' || fail "report: the adaptive scale"
h = open("scaled.html").read()
assert 'data-verdict="failed">Adaptive process noise' in h and "ended at ×350000" in h, "adaptive"
PY

# Malformed thresholds and fit_quality: exit 2 naming the file and the key.
echo '{"bench": {"max_chi2_dof": {"gyro": -1}}}' > t1.json
expect 2 "t1.json: 'bench.max_chi2_dof.gyro'" "$CALBENCH" db approve 1 --operator qc-anna --thresholds t1.json
echo '{"bench": {"max_systematic_residual": {"spin": {"gyro_dph": 1}}}}' > t2.json
expect 2 "t2.json: 'bench.max_systematic_residual.spin': unknown key" "$CALBENCH" db approve 1 --operator qc-anna --thresholds t2.json
echo '{"inmotion": {"mean_nis_per_dof": {"postion": [0.1, 2]}}}' > t3.json
expect 2 "t3.json: 'inmotion.mean_nis_per_dof.postion': unknown key" "$CALBENCH" db approve 1 --operator qc-anna --thresholds t3.json
echo '{"inmotion": {"mean_nis_per_dof": {"default": [2, 0.1]}}}' > t4.json
expect 2 "t4.json: 'inmotion.mean_nis_per_dof.default'" "$CALBENCH" db approve 1 --operator qc-anna --thresholds t4.json
echo '{"combined": {"max_sigma_growth": 0.5}}' > t5.json
expect 2 "t5.json: 'combined.max_sigma_growth'" "$CALBENCH" db approve 1 --operator qc-anna --thresholds t5.json
python3 -c '
import json; c = json.load(open("good.json")); c["fit_quality"]["steps"][3]["kind"] = "spin"; json.dump(c, open("fq1.json", "w"))
c = json.load(open("good.json")); c["fit_quality"]["chi2_per_dof"]["gyro"][1] = -2; json.dump(c, open("fq2.json", "w"))'
expect 2 "fq1.json: 'fit_quality.steps\[3\].kind'" "$CALBENCH" db store-bench --coeffs fq1.json --sha256 "$(printf 'c%.0s' {1..64})"
expect 2 "fq2.json: 'fit_quality.chi2_per_dof.gyro'" "$CALBENCH" db store-bench --coeffs fq2.json --sha256 "$(printf 'c%.0s' {1..64})"
echo "db_fit_verdicts: ok"
