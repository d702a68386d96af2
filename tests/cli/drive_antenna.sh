#!/usr/bin/env bash
# The antenna blocks (issue 34 item 4; docs/in-motion.md, "Lever arm and time offset"): a GNSS-only
# drive of bench/routes/rtk_town.toml (RTK-grade fixes, 5 Hz, 1.5 cm), seed 1, meta.json's lever arm
# moved by (+0.3, -0.3, +0.3) m from the simulated truth and gnss.csv stamped 15 ms late. fit drive
# --estimate lever,time finds both within 3 sigma, the horizontal lever and the time offset with
# sigma below half the prior (the vertical lever, seen through roll and pitch only, ends near 0.06 m),
# and RESULT.json and the summary report them; without --estimate neither key appears. Bad values exit 2.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
python3 - "$SRC/bench/routes/rtk_town.toml" "$T/route.toml" <<'PY'
import sys, re
s = open(sys.argv[1]).read()
s = re.sub(r"\[gnss\]\n(?:[a-z_]+ = [^\n]*\n)*", "[gnss]\nrate_hz = 5.0\nsigma_h_m = 0.015\nsigma_v_m = 0.03\nsigma_vel_m_s = 0.02\n", s, count=1)
open(sys.argv[2], "w").write(s.replace("rate_hz = 400.0", "rate_hz = 100.0"))
PY
grep -q "sigma_h_m = 0.015" "$T/route.toml"
"$CALBENCH" simulate drive --route "$T/route.toml" --truth random --seed 1 --out "$T/rec" >/dev/null
rm "$T/rec/reference.csv"
python3 - "$T/rec" <<'PY'
import json, sys, csv
d = sys.argv[1]
m = json.load(open(d + "/meta.json"))
l = m["mounting"]["lever_arm_m"]
m["mounting"]["lever_arm_m"] = [l[0] + 0.3, l[1] - 0.3, l[2] + 0.3]
json.dump(m, open(d + "/meta.json", "w"), indent=2)
rows = list(csv.reader(open(d + "/gnss.csv")))
h = next(k for k, r in enumerate(rows) if r and not r[0].startswith("#"))
i = rows[h].index("t_s")
for r in rows[h + 1:]:
    r[i] = repr(float(r[i]) + 0.015)
csv.writer(open(d + "/gnss.csv", "w", newline=""), lineterminator="\n").writerows(rows)
PY
"$CALBENCH" fit drive --help > "$T/help.txt"
grep -q -- "--estimate" "$T/help.txt"
"$CALBENCH" fit drive "$T/rec" --out "$T/plain.json" >/dev/null
"$CALBENCH" fit drive "$T/rec" --estimate lever,time --out "$T/est.json" > "$T/summary.txt"
grep -q "^  lever arm " "$T/summary.txt"
grep -q "^  time offset " "$T/summary.txt"
python3 - "$T" <<'PY'
import json, sys
d = sys.argv[1]
p = json.load(open(d + "/plain.json")); e = json.load(open(d + "/est.json"))
assert "lever_arm_m" not in p and "time_offset_s" not in p
l, t = e["lever_arm_m"], e["time_offset_s"]
truth = [-0.3, 0.3, -0.3]  # the correction back to the simulated lever arm
for i in range(3):
    assert abs(l["value"][i] - l["nominal"][i] - l["correction"][i]) < 1e-12, l
    assert abs(l["correction"][i] - truth[i]) <= 3 * l["sigma"][i], (i, l)
    assert l["observable"][i] == (l["sigma"][i] < 0.5 * l["prior"]), (i, l)
    if i < 2:
        assert l["observable"][i], (i, l)
    assert l["sigma"][i] < 0.8 * l["prior"], (i, l)
assert l["prior"] == 0.1 and t["prior"] == 0.02, (l["prior"], t["prior"])
assert abs(t["value"] - 0.015) <= 3 * t["sigma"] and t["sigma"] < 0.5 * t["prior"] and t["observable"], t
print("lever correction", l["correction"], "sigma", l["sigma"], "time offset", t["value"], "sigma", t["sigma"])
PY
# The priors are options.
"$CALBENCH" fit drive "$T/rec" --estimate time --time-offset-sigma 0.05 --json --out "$T/t.json" |
  python3 -c 'import json,sys; r=json.load(sys.stdin); assert "lever_arm_m" not in r and r["time_offset_s"]["prior"] == 0.05'

# Bad input: exit 2 naming the option.
source "$SRC/tests/support/cli_expect.sh"
expect2 "--estimate" "$CALBENCH" fit drive "$T/rec" --estimate lever,clock --out "$T/x.json"
expect2 "--lever-arm-sigma" "$CALBENCH" fit drive "$T/rec" --estimate lever --lever-arm-sigma -0.1 --out "$T/x.json"
expect2 "--time-offset-sigma" "$CALBENCH" fit drive "$T/rec" --estimate time --time-offset-sigma nan --out "$T/x.json"
echo "drive_antenna: ok"
