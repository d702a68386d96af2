#!/usr/bin/env bash
# Real drive (PSINS): the diagnosis's time offset (about −16 ms) applied by the in-motion fit.
# diagnose --out IMPROVED.json, then fit drive on the first 50 s with a set that carries only that
# time offset (b = M = 0, raw-data bias priors: the same filter as without a set) against the same
# set without it: the attitude innovations shrink (mean NIS and gated epochs), and out of sample
# (qc from 50 s) the in-motion set navigates better; the opposite sign is worse. The diagnosis's
# innovation comparison says the same.
set -euo pipefail
D="$SHARED/data/psins-vehicle-100s"
test -d "$D" || { echo "no $D: skipped"; exit 0; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" diagnose "$D" --device-class ADIS16488A --json --out "$T/imp.json" >"$T/d.json"
python3 - "$T" <<'PY'
import json, sys
t = sys.argv[1]
d = json.load(open(t + "/d.json"))
to = [f for f in d["findings"] if f["effect"] == "time_offset"]
assert len(to) == 1 and -0.020 < to[0]["value"] < -0.012, d["findings"]
inn = d["innovations"]
assert inn["after"]["effects_applied"] == ["time_offset"], inn["after"]
a = inn["attitude"]
assert a["after"]["nis_per_dof"] < 0.5 * a["before"]["nis_per_dof"], a
assert a["after"]["rejected"] <= a["before"]["rejected"], a
imp = json.load(open(t + "/imp.json"))
base = {k: v for k, v in imp.items() if k in ("format", "device")}
for s in ("gyro", "accel"):
    base[s] = {"bias": [0, 0, 0], "M": [[0, 0, 0]] * 3, "sigma_bias": [None] * 3, "sigma_M": [[None] * 3] * 3}
json.dump(base, open(t + "/zero.json", "w"))
json.dump(dict(base, time_offset={"s": imp["time_offset"]["s"]}), open(t + "/to.json", "w"))
json.dump(dict(base, time_offset={"s": -imp["time_offset"]["s"]}), open(t + "/wrong.json", "w"))
PY
for s in zero to wrong; do
  "$CALBENCH" fit drive "$D" --device-class ADIS16488A --coeffs "$T/$s.json" --prior-gyro-bias 0.5 --prior-accel-bias 30 --window 0:50 \
    --out "$T/r_$s.json" >/dev/null
done
python3 - "$T" <<'PY'
import json, sys
t = sys.argv[1]
r = {s: json.load(open(f"{t}/r_{s}.json")) for s in ("zero", "to", "wrong")}
att = {s: (r[s]["consistency"]["attitude"]["mean_nis"], r[s]["consistency"]["attitude"]["rejected"]) for s in r}
cpe = {s: [x for x in r[s]["qc"]["sets"] if x["name"] == "in-motion"][0]["final_cpe_m"] for s in r}
print("attitude (mean NIS, rejected):", att, "out-of-sample final ΔS (m):", cpe)
assert r["to"]["effects"]["applied"] == ["time_offset"] and "effects" not in r["zero"]
assert att["to"][0] < 0.5 * att["zero"][0] and att["to"][1] < att["zero"][1], att
assert att["wrong"][0] > att["zero"][0] and att["wrong"][1] > att["zero"][1], att
assert cpe["to"] < cpe["zero"], cpe
PY
echo OK
