#!/usr/bin/env bash
# Temperature terms on a drive through files: a simulated drive gets a warm-up temperature column
# (25 → 55 °C) and a gyro bias that follows it (as imu.csv of a device reporting its temperature
# would); `fit drive --coeffs` with the matching temperature_bias key fits what the same drive
# without the warm-up gives, without the key the gyro drift estimates and the attitude NIS are off.
# On a recording without a temperature column the key is ignored with a note.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" simulate drive --route "$SRC/tests/data/drive_diag_route.toml" --truth random --seed 7 --out "$T/clean" >/dev/null
cp -r "$T/clean" "$T/warm"
python3 - "$T" <<'PY'
import json, math, sys
t = sys.argv[1]
kg = [2e-5, -3e-5, 4e-5]  # rad/s per K (4-8 deg/h/K)
out = []
for line in open(t + "/clean/imu.csv").read().splitlines():
    if line.startswith("#"):
        out.append(line)
    elif line.startswith("t_s"):
        out.append(line + ",temp_c")
    else:
        v = line.split(",")
        temp = 25 + 30 * (1 - math.exp(-float(v[0]) / 60.0))
        for i in range(3):
            v[1 + i] = repr(float(v[1 + i]) + kg[i] * (temp - 25))
        out.append(",".join(v) + "," + repr(round(temp, 3)))
open(t + "/warm/imu.csv", "w").write("\n".join(out) + "\n")
z = {"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": "SIM-7"}}
for s in ("gyro", "accel"):
    z[s] = {"bias": [0, 0, 0], "M": [[0, 0, 0]] * 3, "sigma_bias": [None] * 3, "sigma_M": [[None] * 3] * 3}
json.dump(z, open(t + "/zero.json", "w"))
json.dump(dict(z, temperature_bias={"t0_c": 25, "gyro_rad_s_per_K": kg, "accel_m_s2_per_K": [0, 0, 0]}),
          open(t + "/temp.json", "w"))
PY
fit() { "$CALBENCH" fit drive "$1" --coeffs "$2" --prior-gyro-bias 0.5 --prior-accel-bias 30 --window 0:150 --out "$3" >/dev/null; }
fit "$T/clean" "$T/zero.json" "$T/r_clean.json"
fit "$T/warm" "$T/zero.json" "$T/r_plain.json"
fit "$T/warm" "$T/temp.json" "$T/r_temp.json"
fit "$T/clean" "$T/temp.json" "$T/r_nocol.json"
python3 - "$T" <<'PY'
import json, sys
t = sys.argv[1]
r = {s: json.load(open(f"{t}/r_{s}.json")) for s in ("clean", "plain", "temp", "nocol")}
assert r["temp"]["effects"]["applied"] == ["temperature_bias"], r["temp"]["effects"]
assert r["nocol"]["effects"]["applied"] == [] and r["nocol"]["effects"]["ignored"][0]["key"] == "temperature_bias", r["nocol"]["effects"]
dph = 4.84813681109536e-06
g = {s: [v / dph for v in r[s]["coefficients"]["gyro"]["bias"]] for s in r}
att = {s: r[s]["consistency"]["attitude"]["mean_nis"] for s in r}
print("gyro drift (deg/h):", g, "attitude NIS:", att)
assert max(abs(a - b) for a, b in zip(g["temp"], g["clean"])) < 1.0, g
assert max(abs(a - b) for a, b in zip(g["plain"], g["clean"])) > 20.0, g
assert abs(att["temp"] - att["clean"]) < 0.05 and att["plain"] > att["temp"] + 0.5, att
PY
echo "ok"
