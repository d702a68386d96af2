#!/usr/bin/env bash
# The drive estimators understand IMPROVED.json: simulate a drive with a concealed time offset and
# accelerometer lever arm, diagnose it (--out IMPROVED.json; the JSON's "innovations" compare the
# in-motion filter without and with the found terms), then `fit drive --coeffs IMPROVED.json` says
# it applied both, and its attitude and velocity NIS are lower than with the same coefficients
# without the catalogue keys, which in turn gate out fewer epochs than the time offset with the
# wrong sign (the sign round-trips). `qc` applies the keys of a RESULT.json; bench-only keys are
# ignored with a note; --no-innovations skips the filter runs.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
ROUTE="$SRC/tests/data/drive_diag_route.toml"
"$CALBENCH" simulate drive --route "$ROUTE" --truth random --seed 43 --out "$T/rec" \
  --inject time_offset:value=0.008 --inject lever_arm:y=-0.04 >/dev/null
"$CALBENCH" diagnose "$T/rec" --json --out "$T/improved.json" >"$T/d.json"
python3 - "$T" <<'PY'
import json, sys
t = sys.argv[1]
d = json.load(open(t + "/d.json"))
by = {f["effect"]: f for f in d["findings"]}
assert "time_offset" in by and abs(by["time_offset"]["value"] - 0.008) < 0.0008, d["findings"]
assert "lever_arm" in by and abs(by["lever_arm"]["value"][1] + 0.04) < 0.008, d["findings"]
inn = d["innovations"]
assert inn["compared"] is True, inn
assert inn["after"]["effects_applied"] == ["lever_arm", "time_offset"] and inn["before"]["effects_applied"] == [], inn
for k in ("attitude", "velocity"):
    b, a = inn[k]["before"], inn[k]["after"]
    assert a["nis_per_dof"] < 0.8 * b["nis_per_dof"], (k, b["nis_per_dof"], a["nis_per_dof"])
    assert a["rejected"] <= b["rejected"], (k, b["rejected"], a["rejected"])
    # Not white without the terms, white with them (Ljung-Box, worst normalised component).
    assert b["ljung_box_p_min"] < 1e-6 < 1e-3 < a["ljung_box_p_min"], (k, b["ljung_box_p_min"], a["ljung_box_p_min"])
    assert inn[k]["sentence"].startswith(k), inn[k]["sentence"]
    assert len(b["worst_windows_s"]) >= 1 and len(b["correlations"]) >= 1, b
imp = json.load(open(t + "/improved.json"))
plain = {k: v for k, v in imp.items() if k not in ("time_offset", "lever_arm", "g_sensitivity", "scale_nonlinearity",
                                                    "scale_asymmetry", "correlated_drift", "diagnosis")}
json.dump(plain, open(t + "/plain.json", "w"))
wrong = dict(imp)
wrong["time_offset"] = dict(imp["time_offset"], s=-imp["time_offset"]["s"])
json.dump(wrong, open(t + "/wrong.json", "w"))
# Bench-only keys are ignored by the drive estimator (with a note), not an error.
bench = dict(imp)
bench["misalignment"] = {"table_tilt_rad": [1e-4, 0.0]}
bench["correlated_drift"] = {"gyro_sigma_rad_s": 1e-4, "gyro_tau_s": 60}  # becomes the filter's drift prior
json.dump(bench, open(t + "/bench.json", "w"))
PY
for s in improved plain wrong bench; do
  "$CALBENCH" fit drive "$T/rec" --coeffs "$T/$s.json" --out "$T/r_$s.json" --window 0:150 >"$T/fit_$s.txt"
done
grep -q "catalogue terms applied: lever_arm time_offset" "$T/fit_improved.txt" || { cat "$T/fit_improved.txt"; exit 1; }
grep -q "catalogue term ignored: misalignment" "$T/fit_bench.txt" || { cat "$T/fit_bench.txt"; exit 1; }
python3 - "$T" <<'PY'
import json, sys
t = sys.argv[1]
r = {s: json.load(open(f"{t}/r_{s}.json")) for s in ("improved", "plain", "wrong", "bench")}
assert r["improved"]["effects"]["applied"] == ["lever_arm", "time_offset"], r["improved"]["effects"]
assert abs(r["improved"]["effects"]["time_offset_s"] - 0.008) < 0.0008, r["improved"]["effects"]
assert "effects" not in r["plain"], r["plain"].keys()
assert r["improved"]["coefficients"]["time_offset"]["s"] == r["improved"]["effects"]["time_offset_s"]
assert [i["key"] for i in r["bench"]["effects"]["ignored"]] == ["misalignment"], r["bench"]["effects"]
assert r["bench"]["effects"]["applied"] == ["lever_arm", "time_offset", "correlated_drift"], r["bench"]["effects"]
assert r["bench"]["effects"]["drift_prior"]["gyro"] == {"sigma_si": 1e-4, "T_s": 60}, r["bench"]["effects"]
nis = {s: {k: r[s]["consistency"][k]["mean_nis"] for k in ("position", "velocity", "attitude")} for s in r}
rej = {s: {k: r[s]["consistency"][k]["rejected"] for k in ("position", "velocity", "attitude")} for s in r}
print("mean NIS (expected 3):", nis, "rejected:", rej)
for k in ("attitude", "velocity"):
    assert nis["improved"][k] < 0.8 * nis["plain"][k], (k, nis)
    assert rej["improved"][k] <= rej["plain"][k], (k, rej)
    # The wrong sign is worse than no correction: more epochs gated out.
    assert rej["wrong"][k] > rej["plain"][k], (k, rej)
# QC out of sample from the fit window's end: applied to both sets of the result.
q = r["improved"]["qc"]["sets"]
assert q[0]["name"] == "input" and q[1]["name"] == "in-motion", q
PY
# qc with the RESULT.json applies its keys: a different curve than the same result without them.
"$CALBENCH" qc "$T/rec" --coeffs "$T/r_improved.json" --coeffs "$T/r_plain.json" --json >"$T/qc.json"
python3 - "$T" <<'PY'
import json, sys
q = json.load(open(sys.argv[1] + "/qc.json"))
a, b = q["sets"]
assert a["final_cpe_m"] != b["final_cpe_m"], q
assert a["effects"]["applied"] == ["lever_arm", "time_offset"] and "effects" not in b, q
PY
# --no-innovations skips the filter runs and says so.
"$CALBENCH" diagnose "$T/rec" --json --no-innovations >"$T/d2.json"
python3 -c "import json; d=json.load(open('$T/d2.json')); assert 'skipped' in d['innovations'], d['innovations']"
echo "ok"
