#!/usr/bin/env bash
# simulate multipos (issue 55): a unit of the default class (ICM-42688-P) turned by hand through
# static poses. The recording is a multipos recording (meta.json, imu.csv) with truth.json beside it;
# the truth is checked against the data (each pose's mean specific force is (I + M)·g·up + b), its
# poses against the hand's limits (intervals, unit up vectors spread over the sphere); the same seed
# gives the same file; fit multipos on it finds the truth (compared in the fit's frame, within 5σ of
# the fit's σ and the class's bias wander, and the calibrated gravity magnitude over 500 directions).
# Bad input: the option named, exit 2, nothing written.
set -euo pipefail
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cd "$tmp"

# ---------------------------------------------------------------- the default: short hand-held poses
"$CALBENCH" simulate multipos --out hand --seed 3 > out.txt
grep -Eq "^simulated 24 static poses \(23 turns\), [0-9]+ samples \([0-9.]+ s at 100 Hz\) of one ICM-42688-P unit into hand \(truth in hand/truth.json\)$" out.txt
[ "$(ls hand | tr '\n' ' ')" = "imu.csv meta.json truth.json " ]
[ -z "$(find . -name '.*importing*')" ]
python3 - hand <<'PY'
import csv, json, math, sys
d = sys.argv[1]
meta, truth = json.load(open(d + "/meta.json")), json.load(open(d + "/truth.json"))
assert meta["kind"] == "multipos" and meta["status"] == "complete", meta
assert meta["device"] == {"model": "ICM-42688-P", "serial": "SIM-3"}, meta["device"]
assert meta["imu_rate_hz"] == 100.0 and "site" not in meta
assert truth["format"] == "calbench-coefficients/1" and truth["device"] == meta["device"]
sim, noise = truth["multipos_sim"], truth["noise"]
assert noise["factor"] == 1.0
assert abs(noise["accel"]["white_density_m_s2_sqrt_hz"] / (70e-6 * 9.80665) - 1) < 1e-4, noise  # the class's 70 µg/√Hz
g = sim["gravity_m_s2"]
assert g == 9.80665
rows = [[float(x) for x in r] for r in csv.reader(l for l in open(d + "/imu.csv") if not l.startswith("#")) if r[0] != "t_s"]
assert len(rows) == sim["samples"], (len(rows), sim["samples"])
poses = sim["poses"]
assert len(poses) == 24 and len(sim["turns"]) == 23
last = -1.0
for p in poses:
    assert p["t0_s"] > last and p["t1_s"] >= p["t0_s"], p
    last = p["t1_s"]
    if p["pose"] > 0:
        assert 1.0 - 0.011 <= p["t1_s"] - p["t0_s"] + 0.01 <= 3.0 + 0.011, p  # --still 1,3
    assert abs(math.sqrt(sum(x * x for x in p["up_body"])) - 1) < 1e-12, p
# Distinct gravity directions (within 10° count once), every axis up and down, tilted poses.
dirs = []
for p in poses:
    u = p["up_body"]
    if all(sum(a * b for a, b in zip(u, v)) < math.cos(math.radians(10)) for v in dirs):
        dirs.append(u)
assert len(dirs) >= 18, len(dirs)
for i in range(3):
    assert max(p["up_body"][i] for p in poses) > 0.8 and min(p["up_body"][i] for p in poses) < -0.8, i
assert sum(max(abs(x) for x in p["up_body"]) < math.cos(math.radians(20)) for p in poses) >= 3
# Each pose's mean specific force is the truth's (I + M)·g·up + b, within the noise of the mean and the wander.
A, b = truth["accel"]["M"], truth["accel"]["bias"]
sw, sd = noise["accel"]["white_sigma_per_sample_m_s2"], noise["accel"]["drift_sigma_m_s2"]
for p in poses:
    sel = [r for r in rows if p["t0_s"] - 1e-9 <= r[0] <= p["t1_s"] + 1e-9]
    n = len(sel)
    assert n == round((p["t1_s"] - p["t0_s"]) * 100) + 1, (n, p)
    for i in range(3):
        want = g * sum(((i == j) + A[i][j]) * p["up_body"][j] for j in range(3)) + b[i]
        mean = sum(r[4 + i] for r in sel) / n
        assert abs(mean - want) < 5 * math.hypot(sw / math.sqrt(n), sd), (p["pose"], i, mean, want)
    # Still: the gyros read their bias (no site: no Earth rate) within the noise of the mean and the wander.
    gw, gd = noise["gyro"]["white_sigma_per_sample_rad_s"], noise["gyro"]["drift_sigma_rad_s"]
    for i in range(3):
        mean = sum(r[1 + i] for r in sel) / n
        assert abs(mean - truth["gyro"]["bias"][i]) < 5 * math.hypot(gw / math.sqrt(n), gd), (p["pose"], i)
PY
# The same seed, the same recording; another seed, another.
"$CALBENCH" simulate multipos --out hand2 --seed 3 > /dev/null
cmp hand/imu.csv hand2/imu.csv
cmp hand/truth.json hand2/truth.json
"$CALBENCH" simulate multipos --out hand2 --seed 4 --force > /dev/null
if cmp -s hand/imu.csv hand2/imu.csv; then echo "seeds 3 and 4 gave the same imu.csv" >&2; exit 1; fi
grep -q '"serial": "SIM-4"' hand2/truth.json

# Options into meta.json and truth.json: a unit of no known class, a site, the noise factor.
"$CALBENCH" simulate multipos --out odd --seed 5 --model unknown --serial U7 --site-lat 48 --noise-factor 2 --rate 200 \
  --poses 10 --device-class ADIS16488A > /dev/null 2> note.txt
grep -q "note: no built-in device class is named 'unknown'" note.txt
python3 - odd <<'PY'
import json, sys
meta, truth = json.load(open(sys.argv[1] + "/meta.json")), json.load(open(sys.argv[1] + "/truth.json"))
assert meta["device"] == {"model": "unknown", "serial": "U7"} and meta["imu_rate_hz"] == 200.0
assert meta["site"]["lat_deg"] == 48.0
assert truth["truth"]["device_class"] == "ADIS16488A" and truth["noise"]["factor"] == 2.0
assert abs(truth["noise"]["gyro"]["white_density_rad_s_sqrt_hz"] - 2 * 0.26 / 60 * 3.141592653589793 / 180) < 1e-15
assert abs(truth["multipos_sim"]["gravity_m_s2"] - 9.8089) < 1e-3 and truth["multipos_sim"]["earth_rate"] is True
assert len(truth["multipos_sim"]["poses"]) == 10
PY

# ---------------------------------------------------------------- fit multipos finds the truth
# The truth in the fit's frame (x along the accelerometer x axis, y in its x-y plane: I + M_a = L·Q,
# L lower triangular; the gyros' M then (I + M_g)·Qᵀ − I), as tests/unit/calibration/multipos_fit_test.cpp
# has it. Biases and M within 5·√(σ_fit² + w²): the truth's b is the turn-on bias, the poses see it
# plus the bias wander (truth.json noise.wander_over_poses: its mean over the poses' samples, compared
# with, and w its RMS about that mean). The calibrated gravity magnitude over 500 directions within
# 5 mm/s² (about 0.5 mg; the class's white noise is 0.7 mg per sample).
cat > check_fit.py <<'PY'
import json, math, sys
truth, fit = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
# Poses found: all, each once. Distinct gravity directions: the fit's count equals the truth's, made
# here from the poses' true up vectors (within 10° counted once, greedy in time order, the rule
# docs/multipos.md states).
found, made = len(fit["multipos"]["statics"]), len(truth["multipos_sim"]["poses"])
assert found == made, f"{found} poses found of {made}"
dirs = []
for p in truth["multipos_sim"]["poses"]:
    u = p["up_body"]
    if not any(sum(a * b for a, b in zip(u, d)) > math.cos(math.radians(10)) for d in dirs):
        dirs.append(u)
assert fit["multipos"]["distinct_directions"] == len(dirs), (fit["multipos"]["distinct_directions"], len(dirs))
def mm(A, B): return [[sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
def T(A): return [[A[j][i] for j in range(3)] for i in range(3)]
def mv(A, v): return [sum(A[i][j] * v[j] for j in range(3)) for i in range(3)]
def dot(a, b): return sum(x * y for x, y in zip(a, b))
def plus_i(M, s=1): return [[M[i][j] + s * (i == j) for j in range(3)] for i in range(3)]
A = plus_i(truth["accel"]["M"])
Q, L = [], [[0.0] * 3 for _ in range(3)]
for i in range(3):  # Gram-Schmidt on the rows: A = L·Q
    r = A[i][:]
    for j, q in enumerate(Q):
        L[i][j] = dot(A[i], q)
        r = [x - L[i][j] * y for x, y in zip(r, q)]
    L[i][i] = math.sqrt(dot(r, r))
    Q.append([x / L[i][i] for x in r])
frame = {"accel": plus_i(L, -1), "gyro": plus_i(mm(plus_i(truth["gyro"]["M"]), T(Q)), -1)}
w, g = truth["noise"]["wander_over_poses"], truth["multipos_sim"]["gravity_m_s2"]
unit = {"accel": "m_s2", "gyro": "rad_s"}
worst = (0, "")
for s in ("accel", "gyro"):
    f = fit[s]
    # The poses see the bias b + the wander's mean over them; its spread about that mean is in the bound.
    mean, rms = w[f"{s}_mean_{unit[s]}"], w[f"{s}_rms_about_mean_{unit[s]}"]
    checks = [(f"{s}.bias[{i}]", f["bias"][i], f["sigma_bias"][i], truth[s]["bias"][i] + mean[i], rms[i]) for i in range(3)]
    checks += [(f"{s}.M[{i}][{j}]", f["M"][i][j], f["sigma_M"][i][j], frame[s][i][j], rms[i] / g if s == "accel" else 0)
               for i in range(3) for j in range(3) if s == "gyro" or j <= i]
    for name, est, sig, true, extra in checks:
        z = abs(est - true) / math.hypot(sig, extra)
        worst = max(worst, (z, name))
        assert z <= 5, f"{name}: fit {est:.6g} ± {sig:.3g}, truth {true:.6g} ({z:.1f} sigma)"
def det(m):
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
def solve(M, v):  # Cramer's rule
    return [det([[v[r] if c == k else M[r][c] for c in range(3)] for r in range(3)]) / det(M) for k in range(3)]
At, bt = plus_i(truth["accel"]["M"]), truth["accel"]["bias"]
Af, bf = plus_i(fit["accel"]["M"]), fit["accel"]["bias"]
gmax, n = 0.0, 500
for k in range(n):  # a Fibonacci sphere of directions
    z = 1 - 2 * (k + 0.5) / n
    r, a = math.sqrt(1 - z * z), k * math.pi * (3 - math.sqrt(5))
    m = [x + y for x, y in zip(mv(At, [g * r * math.cos(a), g * r * math.sin(a), g * z]), bt)]
    c = solve(Af, [x - y for x, y in zip(m, bf)])
    gmax = max(gmax, abs(math.sqrt(dot(c, c)) - g))
print(f"worst {worst[1]} at {worst[0]:.2f} sigma; gravity magnitude error over {n} directions at most {gmax * 1e3:.2f} mm/s2")
assert gmax < 0.005, gmax
PY
# Long poses after an opening still interval.
for seed in 7 8; do
  "$CALBENCH" simulate multipos --out fit$seed --seed $seed --still 3,5 --opening-still 20 > /dev/null
  "$CALBENCH" fit multipos fit$seed --json > fit$seed.json
  python3 check_fit.py fit$seed/truth.json fit$seed.json
done
# With a site: the Earth rate in the data, its vertical part removed by --earth-rate.
"$CALBENCH" simulate multipos --out site --seed 9 --still 3,5 --opening-still 20 --site-lat 48 > /dev/null
"$CALBENCH" fit multipos site --earth-rate --json > site.json
python3 check_fit.py site/truth.json site.json
# Hand-held poses of 1-3 s without an opening still interval (issue 55): the class's noise, 3× it in a
# unit of no known class, 0.3× it, 1.5× it with an opening interval of 5 s.
for c in "11 " "12 --noise-factor 3 --model unknown" "13 --noise-factor 0.3" "14 --noise-factor 1.5 --opening-still 5"; do
  set -- $c
  seed=$1; shift
  "$CALBENCH" simulate multipos --out short$seed --seed $seed "$@" > /dev/null 2>&1
  "$CALBENCH" fit multipos short$seed --json > short$seed.json
  python3 check_fit.py short$seed/truth.json short$seed.json
done
python3 - short12.json short14.json <<'PY'
import json, sys
u, o = (json.load(open(p))["multipos"] for p in sys.argv[1:3])
assert u["device_class"]["name"] is None and u["figures_from"]["bias_stability"] == "wide prior (no device class)"
assert u["noise"]["accel_m_s2"]["source"].startswith("quietest"), u["noise"]["accel_m_s2"]
assert o["noise"]["accel_m_s2"]["source"].startswith("opening still interval"), o["noise"]["accel_m_s2"]
PY

# ---------------------------------------------------------------- bad input: exit 2, the option named, nothing written
bad() {  # bad REGEX ARGS...: exit 2, stderr matches, no folder "bad" and no staging folder left
  local pat=$1 rc=0
  shift
  "$CALBENCH" simulate multipos "$@" > /dev/null 2> err.txt || rc=$?
  [ "$rc" = 2 ] || { echo "expected exit 2, got $rc: $*" >&2; cat err.txt >&2; exit 1; }
  grep -Eq -- "$pat" err.txt || { echo "stderr does not match /$pat/: $*" >&2; cat err.txt >&2; exit 1; }
  [ ! -e bad ] && [ -z "$(find . -name '.*importing*')" ] || { echo "left output behind: $*" >&2; exit 1; }
}
bad "--poses: .*'-3'" --out bad --poses -3
bad "--poses: .*'1'" --out bad --poses 1
bad "--still: MIN 3 s is above MAX 1 s" --out bad --still 3,1
bad "--still: expected MIN,MAX" --out bad --still 3
bad "--still: expected MIN,MAX" --out bad --still nan,1
bad "--still: each pose lasts more than 0" --out bad --still 0,1
bad "--device-class: 'nope' is neither a class file nor a known class" --out bad --device-class nope
bad "--noise-factor: .*'-1'" --out bad --noise-factor -1
bad "--rate: .*'0'" --out bad --rate 0
bad "--site-lat: .*'91'" --out bad --site-lat 91
bad "--opening-still: .*'inf'" --out bad --opening-still inf
bad "--out is required" --seed 1
# An existing recording is kept without --force (nothing changed), replaced with it.
before=$(sha256sum hand/imu.csv hand/truth.json hand/meta.json)
rc=0; "$CALBENCH" simulate multipos --out hand --seed 9 > /dev/null 2> err.txt || rc=$?
[ "$rc" = 2 ]
grep -q "hand: already holds a recording (use --force to overwrite)" err.txt
[ "$(sha256sum hand/imu.csv hand/truth.json hand/meta.json)" = "$before" ]
"$CALBENCH" simulate multipos --out hand --seed 9 --force > /dev/null
grep -q '"serial": "SIM-9"' hand/meta.json
grep -q '"seed": 9' hand/truth.json
echo "simulate multipos: OK"
