#!/usr/bin/env bash
# Messages that told the wrong story (issue 17, item 5): an unknown command suggests the nearest; a
# --db that is not a database, a folder as --db or --out, an --out in a missing folder are bad input
# (exit 2) named by the path the user gave; a plan error says that nothing ran.
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
expect() {  # expect RC PATTERN CMD...
  local want=$1 pat=$2; shift 2
  set +e; "$@" > out.txt 2> err.txt; local rc=$?; set -e
  [ "$rc" = "$want" ] || { cat err.txt; fail "exit $rc (expected $want): $*"; }
  grep -q -- "$pat" err.txt || { cat err.txt; fail "message does not match '$pat': $*"; }
}
expect 2 "unknown command 'fti' for 'calbench'; did you mean 'fit'?" "$CALBENCH" fti drive x
expect 2 "unknown command 'drvie' for 'calbench fit'; did you mean 'drive'?" "$CALBENCH" fit drvie x
expect 2 "unknown command 'devcies' for 'calbench db'; did you mean 'devices'?" "$CALBENCH" db devcies
printf 't_s,a\n0,1\n' > notdb.csv
expect 2 "notdb.csv: not a calbench database" "$CALBENCH" db devices --db notdb.csv
mkdir folder
expect 2 "folder: is a folder, not a database file" "$CALBENCH" db devices --db folder
"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 2 --until 40 --out rec > /dev/null
expect 2 "folder: is a folder: give a file name" "$CALBENCH" fit drive rec --out folder
expect 2 "nowhere/r.json: cannot write: the folder nowhere does not exist" "$CALBENCH" fit drive rec --out nowhere/r.json
# An empty --device-class is bad input, not "not given" (every command that takes it).
expect 2 "device-class: expected a value, got an empty one" "$CALBENCH" fit drive rec --device-class "" --out e.json
expect 2 "device-class: expected a value, got an empty one" "$CALBENCH" diagnose rec --device-class ""
expect 2 "device-class: expected a value, got an empty one" "$CALBENCH" simulate drive --out e --device-class " "
expect 2 "device-class: expected a value, got an empty one" "$CALBENCH" simulate multipos --out e --device-class " "
expect 2 "device-class: expected a value, got an empty one" "$CALBENCH" fit multipos rec --device-class ""
[ ! -e e.json ] && [ ! -e e ] || fail "an output written on an empty --device-class"
# An empty output path is bad input, not "no output" (every --out, --report, --plot, --html).
expect 2 "--out: expected a value, got an empty one" "$CALBENCH" diagnose rec --out ""
expect 2 "--report: expected a value, got an empty one" "$CALBENCH" diagnose rec --report ""
expect 2 "--out: expected a value, got an empty one" "$CALBENCH" fit drive rec --out ""
# The logger's timing and the velocity latency (issue 53): auto, off or milliseconds, nothing else.
expect 2 "--sample-time: expected auto, off, or milliseconds in 0 … 1000, got 'fast'" "$CALBENCH" fit drive rec --sample-time fast --out e.json
expect 2 "--gnss-vel-latency: expected auto, off, or milliseconds in 0 … 1000, got '-5'" "$CALBENCH" fit drive rec --gnss-vel-latency -5 --out e.json
expect 2 "--sample-time: expected a value, got an empty one" "$CALBENCH" fit drive rec --sample-time "" --out e.json
[ ! -e e.json ] || fail "an output written on a bad --sample-time"
# A cut last line is dropped with a warning; --json says so (recording.input_warnings).
cp -r rec cut && head -c -7 rec/imu.csv > cut/imu.csv
"$CALBENCH" diagnose cut --no-innovations --json > cut.json 2> cut.err
grep -q "imu.csv:[0-9]*: last line has no line end" cut.err || fail "no warning on the cut last line"
python3 - <<'PY' || fail "--json does not carry the input warning"
import json
w = json.load(open("cut.json"))["recording"]["input_warnings"]
assert len(w) == 1 and w[0]["file"].endswith("cut/imu.csv") and w[0]["line"] > 1 and "no line end" in w[0]["message"], w
PY
ls | grep -q '\.tmp\.' && fail "temporary file left behind"
printf '[plan]\nname = 3\n' > bad.toml
expect 2 "station not started (nothing ran): bad.toml:2" "$CALBENCH" station run --emulated --plan bad.toml --db s.db --out st
# Diagnosis that does not contradict itself (issue 17, item 6): no IMPROVED.json without a finding;
# "white" only with the level it holds at; NIS/dof far below 1 read as too large an assumed noise.
"$CALBENCH" diagnose rec --out imp.json > diag.txt 2> diag.err
if grep -q "^no finding" diag.txt; then
  [ ! -e imp.json ] || fail "IMPROVED.json written without a finding"
  grep -q "imp.json not written" diag.err || fail "not said that --out was not written"
else
  [ -e imp.json ] || fail "a finding but no IMPROVED.json"
fi
grep -q "(white)" diag.txt && fail "'white' without its level"
"$CALBENCH" diagnose "$SHARED/data/psins-vehicle-100s" --device-class ADIS16488A > psins.txt
grep -q "attitude innovations: NIS/dof .* → 0.049.*far below 1: the assumed noise is too large" psins.txt || { grep innovations psins.txt; fail "NIS far below 1 not read as too large a noise"; }
grep -q "Ljung–Box p, worst component) 0 → 0 (not white at the 5 % level)" psins.txt || fail "whiteness level"

# Station care (issue 17, item 8): the next command is printed; a rerun into the same --out is
# refused unless --force; db devices keeps its columns apart.
"$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --db s.db --out st1 > /dev/null 2> run1.txt
grep -q "^next: calbench db approve 1 --db s.db" run1.txt || { cat run1.txt; fail "no next step after the run"; }
grep -Eq "^plan [^:]+: 12 steps, about [0-9.]+ min, about [0-9]+ MB to write into st1 \([0-9]+ MB free\)" run1.txt \
  || { cat run1.txt; fail "no duration and data volume before the run"; }
# A disk that cannot hold the recording is refused before anything moves (a 1 MB tmpfs, where this
# test may mount one: as root, outside a restricted sandbox).
mkdir tiny
if mount -t tmpfs -o size=1m tmpfs tiny 2> /dev/null; then
  set +e; "$CALBENCH" station run --emulated --plan "$SRC/bench/plans/factory.toml" --db tiny/x.db --out tiny/st > /dev/null 2> full.txt; rc=$?; set -e
  umount tiny
  [ "$rc" = 1 ] && grep -q "station not started (nothing ran): not enough free disk space for the recording: the plan writes about 413 MB, 1 MB are free" full.txt \
    || { cat full.txt; fail "a full disk not refused before the run"; }
else
  echo "cli_messages: note: cannot mount a tmpfs here, the free-space refusal is not exercised"
fi
expect 2 "st1: already holds a station run.*--force" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --db s.db --out st1
"$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --db s.db --out st1 --force > /dev/null 2>&1 || fail "--force"
"$CALBENCH" db devices --db s.db > dev.txt
python3 - <<'PY' || fail "db devices columns run together"
rows = [l.rstrip("\n") for l in open("dev.txt")][:2]
head, row = rows
starts = [i for i in range(len(head)) if head[i] != " " and (i == 0 or head[i - 1] == " ")]
for a, b in zip(starts, starts[1:]):  # every field ends before the next column starts, with a space
    assert row[b - 1] == " ", (head, row)
PY
echo "cli_messages: ok"
