#!/usr/bin/env bash
# Parsers that fuzzing broke (issue 17, item 9) and a truncated last line (item 4): each input is
# refused with exit 2 and a message naming the file (and line or field), never a crash or a
# half-written output; a data file whose last line has no line end is read without that line.
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
expect2() {  # expect2 PATTERN CMD...: exit 2 and stderr matches PATTERN
  local pat=$1; shift
  set +e; "$@" > out.txt 2> err.txt; local rc=$?; set -e
  [ "$rc" = 2 ] || { cat err.txt; fail "exit $rc (expected 2): $*"; }
  grep -q -- "$pat" err.txt || { cat err.txt; fail "message does not match '$pat': $*"; }
}

# A minimal bench recording (two rows), for the readers behind `fit bench`.
mkdir bench
cat > bench/meta.json <<'EOF'
{"format": "calbench-recording/1", "kind": "bench", "device": {"model": "ADIS16488A", "serial": "7"},
 "site": {"lat_deg": 48.1, "lon_deg": 11.6, "h_m": 500}, "imu_rate_hz": 100}
EOF
printf 't_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n0,0,0,0,0,0,-9.8\n0.01,0,0,0,0,0,-9.8\n' > bench/imu.csv
printf 't_s,wx_rad_s,wy_rad_s,wz_rad_s,fx_m_s2,fy_m_s2,fz_m_s2,step\n0,0,0,0,0,0,-9.8,0\n0.01,0,0,0,0,0,-9.8,1e10\n' > bench/reference.csv

# A step index of 1e10 overflowed an int (undefined behaviour) and gave a misleading message.
expect2 "reference.csv:3.*'step'.*from −1 to 1000000" "$CALBENCH" fit bench bench --out c.json
[ ! -e c.json ] || fail "output written for bad input"

# meta.json with a value nested 200,000 deep crashed fit bench (segfault in a recursive copy).
python3 -c '
import json
m = json.load(open("bench/meta.json")); s = json.dumps(m)[:-1] + ", \"deep\": " + "[" * 200000 + "]" * 200000 + "}"
open("deep-meta.json", "w").write(s)'
mkdir deep && cp bench/imu.csv bench/reference.csv deep/ && mv deep-meta.json deep/meta.json
expect2 "deep/meta.json:1: JSON nested deeper than 64 levels" "$CALBENCH" fit bench deep --out c.json
# The same nesting in a coefficients file overflowed the stack in a recursive dump.
python3 -c '
open("deep-coeffs.json", "w").write("{\"format\": \"calbench-coefficients/1\", \"x\": " + "{\"a\": " * 100000 + "1" + "}" * 100000 + "}")'
expect2 "deep-coeffs.json:1: JSON nested deeper than 64" "$CALBENCH" db store-bench --db d.db --coeffs deep-coeffs.json --sha256 "$(printf 'a%.0s' {1..64})"
# 64 levels are fine (the limit is documented, not a crash at 65): the error is then about the content.
python3 -c '
open("ok-depth.json", "w").write("{\"format\": \"calbench-coefficients/1\", \"x\": " + "[" * 60 + "]" * 60 + "}")'
set +e; "$CALBENCH" db store-bench --db d.db --coeffs ok-depth.json --sha256 "$(printf 'a%.0s' {1..64})" 2> err.txt; set -e
grep -q "nested deeper" err.txt && fail "60 levels refused as too deep"

# TOML: Debian's toml++ 3.3.0 reaches __builtin_unreachable on a plan that starts with a non-ASCII
# space, or on "[" + NUL; both are refused before the library sees them.
printf '\xc2\xa0[plan]\nname = "x"\n' > nbsp.toml
expect2 "nbsp.toml:1.*U+00A0" "$CALBENCH" simulate bench --plan nbsp.toml --truth random --out s1
printf '[\x00' > nul.toml
expect2 "nul.toml:1.*control character U+0000" "$CALBENCH" simulate bench --plan nul.toml --truth random --out s2
printf '[start]\nlat_deg = 1.0\xe3\x80\x80\n' > ideo.toml
expect2 "ideo.toml:2.*U+3000" "$CALBENCH" simulate drive --route ideo.toml --truth random --out s3
printf '[start]\nlat_deg = 1.0\n# \xff\xfe\n' > utf.toml
expect2 "utf.toml:3.*not valid UTF-8" "$CALBENCH" simulate drive --route utf.toml --truth random --out s4
[ ! -e s1 ] && [ ! -e s2 ] && [ ! -e s3 ] && [ ! -e s4 ] || fail "output written for a refused plan or route"

# KF-GINS: a GNSS line with values near 1.7e308 made import exit 1 and leave a partial recording.
printf '1.00 0 0 0 0 0 0\n1.01 0 0 0 0 0 0\n1.02 0 0 0 0 0 0\n' > imu.txt
printf '0 1.00 30 114 20 0 0 0 0 0 0\n0 1.02 30 114 20 0 0 0 0 0 0\n' > truth.nav
printf '1.00 30 114 20 1 1 1\n1.01 30 114 20 1.7e308 1.7e308 1\n' > gnss.pos
expect2 "gnss.pos:2.*column 5" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --gnss gnss.pos --out kf
[ ! -e kf ] || fail "partial recording left by a failed import"
ls -A | grep -q importing && fail "temporary import folder left behind"
printf '0 1.00 95 114 20 0 0 0 0 0 0\n' > badlat.nav
expect2 "badlat.nav:1.*column 3.*latitude" "$CALBENCH" import kf-gins --imu imu.txt --truth badlat.nav --out kf
[ ! -e kf ] || fail "partial recording left by a failed import"
# A truth.nav or .pos without data rows was imported into a recording calbench then refused to read
# ("reference.csv: no data rows"; found by fuzzing): refused at the import, nothing written.
printf '# no rows\n' > empty.nav
expect2 "empty.nav: no truth rows" "$CALBENCH" import kf-gins --imu imu.txt --truth empty.nav --out kf
printf '%% no rows\n' > empty.pos
expect2 "empty.pos: no GNSS fixes" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --gnss empty.pos --out kf
[ ! -e kf ] || fail "partial recording left by a failed import"
"$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --out kf/ > /dev/null || fail "a good import failed"
[ -s kf/meta.json ] && grep -q '"complete"' kf/meta.json || fail "good import incomplete"

# A truncated last line (cut in the middle of its last number, no line end) is not used: warning
# naming the file and line; the recording's last complete row ends the data.
"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 4 --until 60 --out drv > /dev/null
python3 - <<'PY'
p = "drv/imu.csv"; b = open(p, "rb").read()
assert b.endswith(b"\n")
body = b[:-1]; last = body.rsplit(b"\n", 1)[1]
open(p, "wb").write(body[: len(body) - 3])  # cut inside the last number of the last row
open("last-complete-t", "w").write(body.rsplit(b"\n", 2)[1].split(b",")[0].decode())
PY
"$CALBENCH" fit drive drv --out r.json --qc-horizon 10 > fit.txt 2> err.txt || { cat err.txt; fail "fit drive on a truncated imu.csv"; }
n=$(wc -l < drv/imu.csv); n=$((n + 1))
grep -q "warning: drv/imu.csv:$n: last line has no line end: treated as truncated and not used" err.txt || { cat err.txt; fail "no truncation warning naming the line"; }
python3 - <<'PY' || fail "the cut row was used"
import json
r = json.load(open("r.json")); t = float(open("last-complete-t").read())
assert abs(r["window_s"][1] - t) < 1e-9, (r["window_s"], t)
PY
# A malformed RESULT.json: every reader of it goes through the one codec (common/drive_result.cpp)
# and refuses it the same way, exit 2 naming the file and the key (or the line of a cut file).
python3 - <<'PY'
import json
r = json.load(open("r.json"))
def bad(name, edit):
    k = json.loads(json.dumps(r)); edit(k); json.dump(k, open(name, "w"), indent=2)
bad("r-sha.json", lambda k: k["recording"].__setitem__("sha256", "abc"))
bad("r-mount.json", lambda k: k.__setitem__("mounting_rpy_deg", [1, 2]))
bad("r-bias.json", lambda k: k["coefficients"]["gyro"]["bias"].__setitem__(0, "x"))
bad("r-nis.json", lambda k: k.__setitem__("consistency", {"position": {"epochs": 10, "mean_nis": "x"}}))
bad("r-outage.json", lambda k: k.__setitem__("qc", {"outages": {"sets": [{"name": "none", "per_length": [{"length_s": "15"}]}]}}))
text = open("r.json").read(); open("r-cut.json", "w").write(text[: len(text) // 2])
PY
"$CALBENCH" db init --db h.db > /dev/null
for f in sha:": 'recording.sha256': expected 64 hexadecimal digits" mount:": 'mounting_rpy_deg': expected an array of 3 numbers" \
         bias:": 'coefficients.gyro.bias\[0\]': expected a number" nis:": 'consistency.position.mean_nis': expected a number" \
         outage:": 'qc.outages.sets\[0\].per_length\[0\].length_s': expected a number" cut:":[0-9]*: invalid JSON (truncated or malformed)"; do
  file=r-${f%%:*}.json pat="${f#*:}"
  expect2 "$file$pat" "$CALBENCH" fit drive drv --coeffs $file --out r2.json
  [ ! -e r2.json ] || fail "fit drive wrote a result for $file"
  expect2 "$file$pat" "$CALBENCH" qc drv --coeffs $file --horizon 5
  expect2 "$file$pat" "$CALBENCH" diagnose drv --coeffs $file --no-innovations
  expect2 "$file$pat" "$CALBENCH" db import-inmotion $file --db h.db
done
echo "parsers_hostile_input: ok"
