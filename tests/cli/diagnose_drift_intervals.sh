#!/usr/bin/env bash
# A correlated drift through files: a drive simulated with a gyro drift 20× the data sheet's
# (σ 5e-4 rad/s, τ 60 s) on the 3.6-minute test route, diagnosed without --coeffs. The JSON must
# carry the drift's profile-likelihood intervals (1σ inside 2σ, the estimate inside both; an open
# side null) and the random-walk density K = σ·√(2/τ) with its intervals; K — what a record of a few
# correlation times determines — must be within 20 % of the injected one and inside its 2σ
# interval; the sentence must state K.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" simulate drive --route "$SRC/tests/data/drive_diag_route.toml" --truth random --seed 51 \
  --inject correlated_drift:sensor=gyro,sigma=5e-4,tau=60 --out "$T/d" >/dev/null
"$CALBENCH" diagnose "$T/d" --json --no-innovations >"$T/d.json"
"$CALBENCH" diagnose "$T/d" --no-innovations >"$T/d.txt"
python3 - "$T/d.json" <<'PY'
import json, math, sys
d = json.load(open(sys.argv[1]))
f = [x for x in d["findings"] if x["effect"] == "correlated_drift"]
assert len(f) == 1 and f[0]["sensor"] == "gyro", d["findings"]
f = f[0]
e, s = f["evidence"], f["value"]
def inside(v, lo, hi):
    return (lo is None or lo <= v) and (hi is None or v <= hi)
def nested(inner, outer):
    lo_ok = outer[0] is None or (inner[0] is not None and outer[0] <= inner[0])
    hi_ok = outer[1] is None or (inner[1] is not None and inner[1] <= outer[1])
    return lo_ok and hi_ok
for key in ("sigma", "tau_s", "random_walk_density"):
    one, two = e[key + "_1sigma"], e[key + "_2sigma"]
    assert nested(one, two), (key, one, two)
assert inside(s, *e["sigma_1sigma"]), (s, e["sigma_1sigma"])
assert inside(e["tau_s"], *e["tau_s_1sigma"]), (e["tau_s"], e["tau_s_1sigma"])
k = e["random_walk_density"]
assert abs(k - s * math.sqrt(2 / e["tau_s"])) < 1e-12 * k
assert inside(k, *e["random_walk_density_1sigma"]), (k, e["random_walk_density_1sigma"])
k_true = 5e-4 * math.sqrt(2 / 60)
assert abs(k / k_true - 1) <= 0.2, (k, k_true)
assert inside(k_true, *e["random_walk_density_2sigma"]), (k_true, e["random_walk_density_2sigma"])
print("sigma %.3g (1σ %s, 2σ %s), tau %.3g s (1σ %s), K %.3g vs %.3g injected (1σ %s)" % (
    s, e["sigma_1sigma"], e["sigma_2sigma"], e["tau_s"], e["tau_s_1sigma"], k, k_true,
    e["random_walk_density_1sigma"]))
PY
grep -q "random-walk density σ·√(2/τ)" "$T/d.txt" || { cat "$T/d.txt"; exit 1; }
echo ok
