#!/usr/bin/env bash
# Vehicle constraints (issue 34, item 4): `fit drive --obs pos,vel,nhc,zupt` on a GNSS-only drive
# whose true mounting is 2 deg in pitch and -2.5 deg in yaw (vehicle axes) off the nominal one. Without the
# constraints the mounting stays near its 1 deg prior; with them pitch and yaw become observable
# (posterior sigma below half the prior, error within 3 sigma), and RESULT.json and the summary say
# so, with the standstills found and the constraint updates used/rejected. Bad values exit 2.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
# The short test route at 100 Hz; the truth of seed 5 with its mounting moved off the nominal one.
sed -e 's/^rate_hz = 400.0/rate_hz = 100.0/' "$SRC/bench/routes/short.toml" > "$T/route.toml"
"$CALBENCH" simulate drive --route "$T/route.toml" --truth random --seed 5 --out "$T/r0" >/dev/null
python3 - "$T/r0/truth.json" "$T/truth.json" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))
# Nominal (0, 0, 90): the MEMS x axis is the vehicle's y. Euler roll 2 deg (about MEMS x) is a
# vehicle pitch of 2 deg, Euler pitch -0.3 deg a vehicle roll of 0.3 deg, yaw -2.5 deg.
t["mounting"]["rpy_deg"] = [2.0, -0.3, 90.0 - 2.5]
json.dump(t, open(sys.argv[2], "w"))
PY
"$CALBENCH" simulate drive --route "$T/route.toml" --truth "$T/truth.json" --seed 5 --out "$T/rec" >/dev/null
rm "$T/rec/reference.csv"   # GNSS fixes only

"$CALBENCH" fit drive "$T/rec" --obs pos,vel --out "$T/plain.json" >/dev/null
"$CALBENCH" fit drive "$T/rec" --obs pos,vel,nhc,zupt --out "$T/nhc.json" > "$T/summary.txt"
grep -q "NIS nhc: mean" "$T/summary.txt"
grep -q "standstills .* found" "$T/summary.txt"
grep -q "mounting sigma   prior -> posterior" "$T/summary.txt"
python3 - "$T/plain.json" "$T/nhc.json" <<'PY'
import json, sys, math
p, r = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
assert "vehicle_constraints" not in p and set(p["consistency"]) == {"position", "velocity"}, p["consistency"].keys()
assert r["observations"] == "pos,vel,nhc,zupt"
c = r["consistency"]
for k, dof in (("nhc", 2), ("zupt", 3), ("zero_rate", 3)):
    assert c[k]["expected_nis"] == dof and c[k]["epochs"] > 50, (k, c[k])
    assert c[k]["rejected"] <= 0.02 * c[k]["epochs"] + 1, (k, c[k])
    assert c[k]["mean_nis"] < 3 * dof, (k, c[k])
vc = r["vehicle_constraints"]
# The route's stops: 20 s at the start, 8 s ones later; each longer than the window is found.
st = vc["standstills_s"]
assert st[0][0] < 2 and st[0][1] > 15, st
assert len(st) >= 4, st
m = vc["mounting_sigma_deg"]
assert m["observable"][1] and m["observable"][2], m
def dcm(rpy_deg):  # C = Rz(yaw) Ry(pitch) Rx(roll)
    r, p, y = (math.radians(a) for a in rpy_deg)
    Rx = [[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]]
    Ry = [[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]]
    Rz = [[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]]
    mul = lambda A, B: [[sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    return mul(Rz, mul(Ry, Rx))
def err_deg(res, truth_rpy):  # vehicle-axes misalignment, estimate minus truth: C_true C_est^T = I + d x
    Ce, Ct = dcm(res["mounting_rpy_deg"]["value"]), dcm(truth_rpy)
    D = [[sum(Ct[i][k] * Ce[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    return [math.degrees((D[2][1] - D[1][2]) / 2), math.degrees((D[0][2] - D[2][0]) / 2), math.degrees((D[1][0] - D[0][1]) / 2)]
true = [2.0, -0.3, 87.5]
e, pe = err_deg(r, true), err_deg(p, true)
for i, name in ((1, "pitch"), (2, "yaw")):
    sig, psig = m["posterior"][i], m["prior"][i]
    assert abs(e[i]) <= 3 * sig and sig < 0.5 * psig, (name, e[i], sig, psig)
    print("vehicle %s: error %.2f deg with pos,vel; %.3f +- %.3f deg with nhc,zupt (prior sigma %.1f)" % (name, pe[i], e[i], sig, psig))
PY

# Bad values: exit 2 naming what is wrong.
source "$SRC/tests/support/cli_expect.sh"
expect2 "unknown observation 'nhx'" "$CALBENCH" fit drive "$T/rec" --obs pos,nhx --out "$T/x.json"
expect2 "add pos, vel or att" "$CALBENCH" fit drive "$T/rec" --obs nhc,zupt --out "$T/x.json"
expect2 "constraint-rate" "$CALBENCH" fit drive "$T/rec" --obs pos,nhc --constraint-rate 0 --out "$T/x.json"
expect2 "constraint-rate" "$CALBENCH" fit drive "$T/rec" --obs pos,nhc --constraint-rate nan --out "$T/x.json"
expect2 "nhc-sigma" "$CALBENCH" fit drive "$T/rec" --obs pos,nhc --nhc-sigma -0.1 --out "$T/x.json"
expect2 "zupt-sigma" "$CALBENCH" fit drive "$T/rec" --obs pos,zupt --zupt-sigma abc --out "$T/x.json"
[ ! -e "$T/x.json" ]
# A sigma for a constraint that is not used is named, not silently dropped.
"$CALBENCH" fit drive "$T/rec" --obs pos,vel,zupt --nhc-sigma 0.2 --out "$T/y.json" > /dev/null 2> "$T/err.txt"
grep -q -- "--nhc-sigma.*no effect" "$T/err.txt"
"$CALBENCH" fit drive --help > "$T/help.txt"
grep -q -- "--constraint-rate" "$T/help.txt" && grep -q "nhc" "$T/help.txt"
echo "drive_nhc_zupt: ok"
