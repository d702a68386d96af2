#!/usr/bin/env bash
# calbench report SERIAL --html and report fleet --html: the pages open in headless Chromium, every
# embedded plot decodes, and what the page shows is what a QC engineer signs (page JS marks <body>
# with what the browser laid out; the tables are read from the DOM Chromium dumps):
#  - a combined set: per-coefficient table bench → combined with σ and the stage of each of the 24
#    coefficients (from RESULT.json "determined_by"), the reference system, full SHA-256 digests,
#    ΔS(t) drawn from the series with more than 10 browser-parsed points per curve over the whole
#    horizon, QC metrics with threshold and in-/out-of-sample, the consistency table with verdicts;
#    the set passes the thresholds, is approved, and the page says PASS naming them;
#  - a combined set worse than its parent out of sample (an older RESULT.json without series,
#    determined_by or reference): FAIL with the reason on the page, stage "–" with the reason.
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
export CALBENCH_DB="$T/r.db"
CHROMIUM=$(command -v chromium || command -v chromium-browser || true)
[ -n "$CHROMIUM" ] || fail "chromium not installed (scripts/setup installs it)"

python3 - <<'PY'
import json, math, random
r = random.Random(5)
def tri(bias, scale=1.0):
    return {"bias": [r.gauss(0, bias) for _ in range(3)],
            "M": [[r.gauss(0, (3e-3 if i == j else 3e-4) * scale) for j in range(3)] for i in range(3)],
            "sigma_bias": [bias / 100] * 3, "sigma_M": [[2e-5] * 3 for _ in range(3)]}
def coeffs(serial, g, a):
    return {"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": serial}, "gyro": g, "accel": a}
bench = {}
for i in range(12):
    g = tri(1e-3)
    if i == 11: g["M"][0][0] = 0.2   # a gross outlier
    bench["U%02d" % i] = (g, tri(0.05))
    json.dump(coeffs("U%02d" % i, *bench["U%02d" % i]), open("u%02d.json" % i, "w"))
# The in-motion correction estimates only biases here, so the combined set is b = b1 + (I+M1)·b2, M = M1.
def combined(parent, corr_bias, sigma_bias):
    out = {}
    for k, t in zip(("gyro", "accel"), parent):
        A = [[(1.0 if i == j else 0.0) + t["M"][i][j] for j in range(3)] for i in range(3)]
        b = [t["bias"][i] + sum(A[i][m] * corr_bias[k][m] for m in range(3)) for i in range(3)]
        out[k] = {"bias": b, "M": t["M"], "sigma_bias": [sigma_bias[k]] * 3, "sigma_M": t["sigma_M"]}
    return out
names = [f"{t}.bias.{a}" for t in ("gyro",) for a in "xyz"] + [f"gyro.M.{a}{b}" for a in "xyz" for b in "xyz"] + \
        [f"accel.bias.{a}" for a in "xyz"] + [f"accel.M.{a}{b}" for a in "xyz" for b in "xyz"]
def result(serial, corr_bias, series, worse=False):
    tot = combined(bench[serial], corr_bias, {"gyro": 2e-6, "accel": 3e-4})
    horizon = 300.0
    def curve(k):  # ΔS grows about as t²
        ts = [0.02] + [float(s) for s in range(1, 301)]
        return {"t_s": ts, "cpe_m": [round(k * t * t, 4) for t in ts]}
    base, res = (2e-3, 3e-3) if worse else (2e-3, 1e-4)
    sets = [{"name": "input", "final_cpe_m": base * horizon ** 2, "max_cpe_m": base * horizon ** 2,
             "cpe_m_at": {"10": base * 100, "60": base * 3600, "300": base * horizon ** 2}},
            {"name": "in-motion", "final_cpe_m": res * horizon ** 2, "max_cpe_m": res * horizon ** 2,
             "cpe_m_at": {"10": res * 100, "60": res * 3600, "300": res * horizon ** 2}}]
    if series:
        sets[0]["cpe_series"], sets[1]["cpe_series"] = curve(base), curve(res)
    j = {"device": {"model": "ADIS16488A", "serial": serial},
         "recording": {"path": "/drives/d<1>", "sha256": "cd" * 32, "sha256_reference": "e1" * 32, "sha256_meta": "f2" * 32},
         "window_s": [0, 200], "observations": "pos,vel,att",
         "coefficients": coeffs(serial, tot["gyro"], tot["accel"]),
         "correction": {k: {"bias": corr_bias[k], "M": [[0] * 3 for _ in range(3)], "sigma_bias": [1e-6] * 3,
                            "sigma_M": [[1e-3] * 3 for _ in range(3)]} for k in ("gyro", "accel")},
         "mounting_rpy_deg": {"value": [0.1, -0.2, 0.3], "sigma": [0.01, 0.01, 0.05]},
         "consistency": {"position": {"equation": "13", "epochs": 2000, "rejected": 0, "forced": 0, "mean_nis": 3.01,
                                      "expected_nis": 3.0, "fraction_within_95pct": 0.951},
                         "velocity": {"equation": "14", "epochs": 2000, "rejected": 3, "forced": 0, "mean_nis": 4.2,
                                      "expected_nis": 3.0, "fraction_within_95pct": 0.90},
                         "attitude": {"equation": "15", "epochs": 2000, "rejected": 0, "forced": 0, "mean_nis": 0.4,
                                      "expected_nis": 3.0, "fraction_within_95pct": 1.0}},
         "qc": {"from_s": 200.0, "horizon_s": horizon, "sample": "out-of-sample (after the fit window)", "sets": sets}}
    if series:  # what fit drive writes since issue 16
        j["reference_system"] = "FOG INS <ref> (reference.csv: 50 Hz); observations used: position (eq 13)"
        stages = ["drive", "bench", "both"]
        share = {"drive": 0.99, "bench": 0.05, "both": 0.5}  # consistent with the rule (import checks it)
        j["determined_by"] = {"rule": "drive share of the information 1-(sigma_post/sigma_prior)^2: < 0.2 bench, > 0.8 drive, else both",
                              "coefficients": {n: {"parent_sigma": 1e-5, "prior_sigma": 4.9e-4,
                                                   "posterior_sigma": 4.9e-4 * (1 - share[stages[i % 3]]) ** 0.5,
                                                   "ratio": (1 - share[stages[i % 3]]) ** 0.5,
                                                   "drive_share": share[stages[i % 3]], "stage": stages[i % 3]}
                                               for i, n in enumerate(names)}}
        j["priors"] = {"mode": "input set", "device_class": "ADIS16488A", "parameters": {}}
    return j
json.dump(result("U00", {"gyro": [1e-4, -2e-4, 5e-5], "accel": [0.01, -0.02, 0.005]}, True), open("good.json", "w"))
json.dump(result("U01", {"gyro": [3e-4, 1e-4, 0.0], "accel": [0.0, 0.01, 0.0]}, False, worse=True), open("worse.json", "w"))
PY
"$CALBENCH" db init >/dev/null
k=0
for f in u*.json; do  # ended 10 min apart, the newest now: all within the fleet page's last 24 h
  k=$((k + 1))
  "$CALBENCH" db store-bench --coeffs "$f" --sha256 "$(printf 'a%.0s' {1..64})" --plan "factory <plan>" \
    --ended "$(date -u -d "-$((k * 10)) min" +%Y-%m-%dT%H:%M:%SZ)" --station "line-$((k % 2 + 1))" \
    --qc gyro_resid_rms=1e-5:1e-4:rad/s:in-sample >/dev/null
done
"$CALBENCH" db approve 1 --operator qc-anna >/dev/null   # U00's bench set
"$CALBENCH" db approve 2 --operator qc-anna >/dev/null   # U01's bench set
"$CALBENCH" db import-inmotion good.json --json | python3 -c 'import json,sys; o=json.load(sys.stdin); assert o["source"] == "combined" and o["parent"] == 1, o'
"$CALBENCH" db import-inmotion worse.json --json | python3 -c 'import json,sys; o=json.load(sys.stdin); assert o["source"] == "combined" and o["parent"] == 2, o'
# The good combined set (better than its parent out of sample, σ within limits) is approvable;
# the worse one is refused for its QC.
"$CALBENCH" db approve 13 --operator qc-anna >/dev/null || fail "a combined set better than its parent was refused"
set +e; "$CALBENCH" db approve 14 --operator qc-anna > /dev/null 2> refused.txt; rc=$?; set -e
[ "$rc" = 1 ] && grep -q "sets.in-motion.final_cpe_m" refused.txt || { cat refused.txt; fail "a combined set worse than its parent was approved"; }
"$CALBENCH" report U00 --html dev.html >/dev/null
"$CALBENCH" report U01 --html worse.html >/dev/null
"$CALBENCH" report fleet --html fleet.html >/dev/null
grep -q "U11" fleet.html || fail "outlier U11 not flagged in the fleet table"
grep -q "factory &lt;plan&gt;" dev.html || fail "text not escaped"

check() {  # check PAGE MIN_IMAGES: load in Chromium at 1200 px, all images decoded, nothing wider than the window
  "$CHROMIUM" --headless --no-sandbox --disable-gpu --no-first-run --disable-background-networking \
    --disable-component-update --disable-sync --user-data-dir="$T/profile" --virtual-time-budget=5000 \
    --window-size=1200,3000 --dump-dom "file://$T/$1" > "$1.dom" 2> "$1.err" || { tail -5 "$1.err"; fail "chromium failed on $1"; }
  local n w
  n=$(grep -o 'data-images="[0-9]*/[0-9]*"' "$1.dom" | head -1 | tr -dc '0-9/')
  [ -n "$n" ] || fail "$1: the page did not finish loading in the browser"
  [ "${n%/*}" = "${n#*/}" ] || fail "$1: only $n images decoded"
  [ "${n#*/}" -ge "$2" ] || fail "$1: $n images, expected at least $2"
  w=$(grep -o 'data-scroll-width="[0-9]*"' "$1.dom" | head -1 | tr -dc '0-9')
  [ -n "$w" ] && [ "$w" -le 1200 ] || fail "$1: laid out $w px wide at a 1200 px window (text cut)"
  echo "$1: $n images decoded, $w px wide"
}
check dev.html 0       # its plots are inline SVG (counted below)
check worse.html 0
check fleet.html 0
# Inline SVG plots: the coefficient history (4) in each device report; in the fleet report a
# histogram per coefficient (24), outliers drawn as red points, and the units per hour.
[ "$(grep -o '<svg[^>]*class="history"' dev.html.dom | wc -l)" = 4 ] || fail "dev.html: expected 4 coefficient-history plots"
[ "$(grep -o '<svg[^>]*class="history"' worse.html.dom | wc -l)" = 4 ] || fail "worse.html: expected 4 coefficient-history plots"
[ "$(grep -o '<svg[^>]*class="histogram"' fleet.html.dom | wc -l)" = 24 ] || fail "fleet.html: expected 24 histograms"
grep -q '<g data-curve="outliers"' fleet.html.dom || fail "fleet.html: outliers not drawn"
grep -q '<svg[^>]*class="throughput"' fleet.html.dom || fail "fleet.html: no units-per-hour plot"
python3 - "$k" <<'PY' || fail "fleet.html: units per hour do not count the stored runs"
import re, sys
dom = open("fleet.html.dom").read()
rows = re.findall(r'<tr data-station="(line-[12])"><td[^>]*>[^<]*</td><td>(\d+)</td><td>(\d+)</td>', dom)
assert sorted(r[0] for r in rows) == ["line-1", "line-2"], rows
assert sum(int(r[2]) for r in rows) == int(sys.argv[1]), (rows, sys.argv[1])
assert sum(int(r[1]) for r in rows) == 5, rows  # ended 10 to 50 min ago: five within the last hour
PY

python3 - good.json worse.json <<'PY' || fail "device report content"
import json, re, sys
from html.parser import HTMLParser

class Dom(HTMLParser):
    """Elements with their attributes and text, tables by id as rows of (tr attrs, [cell attrs, cell text])."""
    def __init__(s):
        super().__init__(); s.stack = []; s.tables = {}; s.body = {}; s.by_id = {}; s.table = None; s.row = None; s.cell = None
    def handle_starttag(s, tag, attrs):
        a = dict(attrs)
        if tag == "body": s.body = a
        if "id" in a: s.by_id[a["id"]] = [a, ""]; s.stack.append((tag, a["id"]))
        else: s.stack.append((tag, None))
        if tag == "table": s.table = s.tables.setdefault(a.get("id", "?%d" % len(s.tables)), [])
        if tag == "tr" and s.table is not None: s.row = (a, []); s.table.append(s.row)
        if tag in ("td", "th") and s.row is not None: s.cell = [a, "", tag]; s.row[1].append(s.cell)
    def handle_endtag(s, tag):
        while s.stack:
            t, _ = s.stack.pop()
            if t == tag: break
        if tag == "table": s.table = None
        if tag in ("td", "th"): s.cell = None
    def handle_data(s, d):
        if s.cell is not None: s.cell[1] += d
        for _, i in s.stack:
            if i: s.by_id[i][1] += d
def load(page):
    d = Dom(); d.feed(open(page + ".dom").read()); return d
def data_rows(t):
    return [r for r in t if r[1] and r[1][0][2] == "td"]

good, worse = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
d = load("dev.html")
# ΔS: every curve (two sets × linear and log panel) as parsed by the browser, over the whole horizon.
assert int(d.body.get("data-cpe-curves", 0)) == 4, d.body
assert int(d.body["data-cpe-min-points"]) > 10, d.body
assert int(d.body["data-cpe-min-points"]) == len(good["qc"]["sets"][0]["cpe_series"]["t_s"]), d.body
assert float(d.body["data-cpe-min-span"]) >= 0.95, d.body
# Verdict PASS, thresholds named (in-motion run 1 is U00's, run 2 U01's).
assert d.by_id["verdict"][0]["data-verdict"] == "PASS", d.by_id["verdict"]
assert "gyro: |bias|" in d.by_id["thresholds"][1], d.by_id["thresholds"]
assert "verdict-reasons" not in d.by_id
# Reference named; digests in full.
html = open("dev.html.dom").read()
assert "FOG INS &lt;ref&gt;" in html
for k in ("sha256", "sha256_reference", "sha256_meta"):
    assert re.search(r'<span class="digest">' + good["recording"][k] + "</span>", html), k
# Per-coefficient table: 24 rows, bench and combined with σ, the stage of each from determined_by.
rows = data_rows(d.tables["stages-1"])
assert len(rows) == 24, len(rows)
for tr, cells in rows:
    name = cells[0][1].strip()
    assert cells[8][0]["data-stage"] == good["determined_by"]["coefficients"][name]["stage"], (name, cells[8])
    assert "±" in cells[2][1] and "±" in cells[3][1], cells
    assert cells[1][1].strip() in ("°/h", "mg", "ppm"), cells[1]
# QC: threshold and in/out-of-sample on every row; the result's final ΔS checked against its parent's.
q = {cells[0][1].strip(): (tr, cells) for tr, cells in data_rows(d.tables["qc-inmotion-1"])}
assert all(tr["data-sample"] == "out-of-sample" for tr, _ in q.values()), q
tr, cells = q["sets.in-motion.final_cpe_m"]
assert abs(float(tr["data-threshold"]) - good["qc"]["sets"][0]["final_cpe_m"]) < 1e-3 and cells[6][1] == "pass", cells
assert q["sets.input.final_cpe_m"][1][6][1] == "informative", q["sets.input.final_cpe_m"]
# Consistency: one row per observation type with a verdict the statistics support.
c = {cells[0][1].strip(): tr["data-verdict"] for tr, cells in data_rows(d.tables["consistency-1"])}
assert c == {"position": "consistent", "velocity": "too-large", "attitude": "too-small"}, c

w = load("worse.html")
assert w.by_id["verdict"][0]["data-verdict"] == "FAIL", w.by_id["verdict"]
reasons = w.by_id["verdict-reasons"][1]
assert "sets.in-motion.final_cpe_m" in reasons and "never worse than the set the fit started from" in reasons, reasons
assert all(cells[8][0]["data-stage"] == "–" for _, cells in data_rows(w.tables["stages-2"]))
assert "no &quot;determined_by&quot;" in open("worse.html.dom").read() or 'no "determined_by"' in open("worse.html.dom").read()
assert "not recorded in this result" in open("worse.html.dom").read()   # reference system of an older result
assert int(w.body["data-cpe-min-points"]) <= 10   # only the marks: drawn, and said so
PY
echo "db_report_browser: ok"
