#!/usr/bin/env bash
# import csv --kind multipos (issue 37): a generic logger's CSV (header line; comma, semicolon, tab or
# blanks; columns by name or 1-based index; deg/s, g, ms; rates or increments) into a multipos
# recording that fit multipos reads. Made from IMU-TK's real xsens recording (converted by import
# imu-tk), re-written in the units of a logger: the fit on the CSV import must equal the fit on the
# imu-tk import. Bad input: file, line and column named, exit 2, nothing written.
set -euo pipefail
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
D="$SHARED/data/imu_tk-xsens-multipos"
[ -f "$D/xsens_acc.mat" ] || { echo "no $D: skipped"; exit 77; }
conv=(--acc-offset 32768 --acc-scale 0.0026808 --gyro-offset 32768 --gyro-scale 1.5979e-4 --gravity 9.81744)
"$CALBENCH" import imu-tk "$D/xsens_acc.mat" "$D/xsens_gyro.mat" --out "$tmp/xs" "${conv[@]}" --model "Xsens MTi" --serial XS1 > /dev/null
"$CALBENCH" fit multipos "$tmp/xs" --json > "$tmp/ref.json"
# An import killed by Ctrl-C leaves its hidden staging copy (.NAME.importing-PID): the next import of
# NAME removes it when that process is gone, and leaves a live process's alone (issue 56 item 11).
mkdir -p "$tmp/.xs2.importing-999999" "$tmp/.xs2.importing-$$"
head -c 100000 "$tmp/xs/imu.csv" > "$tmp/.xs2.importing-999999/imu.csv"
"$CALBENCH" import imu-tk "$D/xsens_acc.mat" "$D/xsens_gyro.mat" --out "$tmp/xs2" "${conv[@]}" --serial XS1 > /dev/null 2>&1
[ ! -e "$tmp/.xs2.importing-999999" ] || { echo "stale staging folder left"; exit 1; }
[ -d "$tmp/.xs2.importing-$$" ] || { echo "a live process's staging folder removed"; exit 1; }
# The same rows as a logger writes them: ms, deg/s, g; semicolons; extra columns; columns in another order.
python3 - "$tmp/xs/imu.csv" "$tmp" <<'PY'
import csv, math, sys
rows = [{k.split('_')[0]: v for k, v in r.items()} for r in csv.DictReader(l for l in open(sys.argv[1]) if not l.startswith('#'))]
out = sys.argv[2]
g0 = 9.80665
with open(out + '/semi.csv', 'w') as f:
    f.write('temp;ACC_Z;ACC_Y;ACC_X;time_ms;GYR_X;GYR_Y;GYR_Z\n')
    for r in rows:
        f.write('25.0;%.17g;%.17g;%.17g;%.17g;%.17g;%.17g;%.17g\n' % (
            float(r['az']) / g0, float(r['ay']) / g0, float(r['ax']) / g0, float(r['t']) * 1e3,
            math.degrees(float(r['gx'])), math.degrees(float(r['gy'])), math.degrees(float(r['gz']))))
with open(out + '/tab.csv', 'w') as f:
    f.write('t\tgx\tgy\tgz\tax\tay\taz\n')
    for r in rows:
        f.write('\t'.join(r[k] for k in ('t', 'gx', 'gy', 'gz', 'ax', 'ay', 'az')) + '\n')
PY
"$CALBENCH" import csv "$tmp/semi.csv" --kind multipos --out "$tmp/semi" --time time_ms --time-unit ms \
  --gyro GYR_X,GYR_Y,GYR_Z --gyro-unit deg/s --accel 4,3,2 --accel-unit g --gravity 9.81744 --model "Xsens MTi" --serial XS1 > "$tmp/imp.txt"
grep -q "imported 51175 rows (100 Hz, semicolon-separated)" "$tmp/imp.txt"
"$CALBENCH" fit multipos "$tmp/semi" --json > "$tmp/semi.json"
"$CALBENCH" import csv "$tmp/tab.csv" --kind multipos --out "$tmp/tab" --gravity 9.81744 --model MTi --serial XS1 > "$tmp/imp2.txt"
grep -q "blanks-separated" "$tmp/imp2.txt"
"$CALBENCH" fit multipos "$tmp/tab" --json > "$tmp/tab.json"
python3 - "$tmp/ref.json" "$tmp/semi.json" "$tmp/tab.json" "$tmp/semi/meta.json" <<'PY'
import json, sys
ref, semi, tab, meta = (json.load(open(p)) for p in sys.argv[1:5])
assert meta["kind"] == "multipos" and meta["gravity_m_s2"] == 9.81744
def flat(j):
    m = j["multipos"]
    return [m["g_spread_m_s2"], m["rotation_rms_deg"], len(m["statics"])]
for other in (semi, tab):
    a, b = flat(ref), flat(other)
    assert b[2] == a[2], (a, b)
    assert abs(a[0] - b[0]) <= 1e-6 * max(1e-3, a[0]) + 1e-9, (a, b)
    assert abs(a[1] - b[1]) <= 1e-6 * max(1e-3, a[1]) + 1e-9, (a, b)
PY
# Increments (per sample) give the same recording's rates back.
printf 't,dth_x,dth_y,dth_z,dv_x,dv_y,dv_z\n0,0,0,0,0,0,0.0981\n0.01,0.0001,0,0,0,0,0.0981\n0.02,0,0,0,0,0.0981,0\n' > "$tmp/inc.csv"
"$CALBENCH" import csv "$tmp/inc.csv" --kind multipos --out "$tmp/inc" --increments --time 1 --gyro 2,3,4 --accel 5,6,7 --model MTi --serial XS1 > /dev/null
python3 - "$tmp/inc/meta.json" "$tmp/inc/imu.csv" <<'PY'
import json, sys
meta = json.load(open(sys.argv[1]))
hdr = [l for l in open(sys.argv[2]) if not l.startswith('#')][0]
assert "dtheta" in hdr or "dth" in hdr or "dv" in hdr, hdr
PY
# Bad input: exit 2, file + line + column, nothing written.
bad() {  # name, expected message part, file content, options...
  local name=$1 want=$2 content=$3; shift 3
  printf "$content" > "$tmp/$name.csv"
  set +e; "$CALBENCH" import csv "$tmp/$name.csv" --kind multipos --out "$tmp/$name" --model MTi --serial XS1 "$@" 2> "$tmp/$name.err"; rc=$?; set -e
  [ $rc -eq 2 ] || { echo "$name: exit $rc"; cat "$tmp/$name.err"; exit 1; }
  grep -q -- "$want" "$tmp/$name.err" || { echo "$name: wanted '$want'"; cat "$tmp/$name.err"; exit 1; }
  [ ! -e "$tmp/$name" ] || { echo "$name: wrote output"; exit 1; }
  ! ls -a "$tmp" | grep -q "^\.$name\.importing" || { echo "$name: left staging"; exit 1; }
}
H='t,gx,gy,gz,ax,ay,az\n'
bad notnum "$tmp/notnum.csv:3.*gy.*not a number" "${H}0,0,0,0,0,0,9.8\n0.01,0,x,0,0,0,9.8\n"
bad nan "$tmp/nan.csv:2.*az.*NaN" "${H}0,0,0,0,0,0,nan\n0.01,0,0,0,0,0,9.8\n"
bad short "$tmp/short.csv:3.*az.*missing field" "${H}0,0,0,0,0,0,9.8\n0.01,0,0,0,0,0\n"
bad backwards "$tmp/backwards.csv:3.*time does not increase" "${H}0,0,0,0,0,0,9.8\n0,0,0,0,0,0,9.8\n"
bad nocol "missing required column" "${H}0,0,0,0,0,0,9.8\n0.01,0,0,0,0,0,9.8\n" --gyro wx,wy,wz
bad noindex "column 9 does not exist" "${H}0,0,0,0,0,0,9.8\n0.01,0,0,0,0,0,9.8\n" --time 9
bad range "$tmp/range.csv:2.*outside" "${H}0,0,0,0,0,0,1e9\n0.01,0,0,0,0,0,9.8\n"
bad onerow "needs at least two data rows" "${H}0,0,0,0,0,0,9.8\n"
bad empty "no header line" ""
bad incrate "$tmp/incrate.csv:3.*angular rate of the increment" "${H}0,0,0,0,0,0,0.098\n0.01,500,0,0,0,0,0.098\n0.02,0,0,0,0,0,0.098\n" --increments
bad dupcol "given for both --gyro x and --gyro y" "${H}0,0,0,0,0,0,9.8\n0.01,0,0,0,0,0,9.8\n" --gyro 2,2,4
bad duphead "names 'gx' 2 times" "t,gx,gx,gz,ax,ay,az\n0,0,0,0,0,0,9.8\n0.01,0,0,0,0,0,9.8\n" --gyro 2,3,4
bad gap "$tmp/gap.csv:4.*not an IMU interval" "${H}0,0,0,0,0,0,9.8\n0.01,0,0,0,0,0,9.8\n4000,0,0,0,0,0,9.8\n"
set +e; "$CALBENCH" import csv "$tmp/inc.csv" --kind multipos --out "$tmp/u" --model MTi --serial XS1 --gyro-unit furlong/s 2> "$tmp/u.err"; rc=$?; set -e
[ $rc -ne 0 ] && grep -q "gyro-unit" "$tmp/u.err"
"$CALBENCH" import csv --help | grep -q -- "--increments"
echo ok
