#!/usr/bin/env bash
# Issue 17 items 2 and 8: every write names its operator; an approval is signed by a named operator
# other than the one who stored the set (four-eyes), relaxed only by an audited database setting;
# bad operator names are bad input (exit 2); an aborted station run is recorded in `db history`
# with its reason; the device report shows the names.
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
unset CALBENCH_OPERATOR CALBENCH_USER
export CALBENCH_DB="$T/s.db" CALBENCH_STATION=line-7
run() { set +e; "$@" > out.txt 2> err.txt; rc=$?; set -e; }

# The station's operator from the environment stores the set.
CALBENCH_OPERATOR="Sam Station" "$CALBENCH" station run --plan "$SRC/tests/data/short_plan.toml" --emulated \
  --db s.db --out run 2> station.txt
grep -q "^next: calbench db approve 1 --db s.db --operator NAME" station.txt || { cat station.txt; fail "next step without --operator"; }
[ "$(sqlite3 s.db "SELECT created_by FROM coefficient_sets WHERE id = 1")" = "Sam Station@line-7" ] || fail "created_by"

# Without a named operator (the OS user only): refused, exit 1, naming both ways to sign.
run "$CALBENCH" db approve 1
[ "$rc" = 1 ] && grep -q "approval needs a named operator: --operator NAME or CALBENCH_OPERATOR" err.txt || { cat err.txt; fail "unsigned approval: exit $rc"; }
# The operator who stored it: four-eyes refusal, exit 1.
run "$CALBENCH" db approve 1 --operator "Sam Station"
[ "$rc" = 1 ] && grep -q "four-eyes: set 1 was stored by 'Sam Station'" err.txt || { cat err.txt; fail "self-approval: exit $rc"; }
[ "$(sqlite3 s.db "SELECT status FROM coefficient_sets WHERE id = 1")" = draft ] || fail "a refusal changed the status"
# Bad names are bad input (exit 2), from the option and from the environment, naming where.
run "$CALBENCH" db approve 1 --operator "qa@lab"
[ "$rc" = 2 ] && grep -q -- "--operator: operator name 'qa@lab' must not contain '@'" err.txt || { cat err.txt; fail "bad --operator: exit $rc"; }
run env CALBENCH_OPERATOR=" " "$CALBENCH" db approve 1
[ "$rc" = 2 ] && grep -q "CALBENCH_OPERATOR: operator name ' ' must not be blank" err.txt || { cat err.txt; fail "blank CALBENCH_OPERATOR: exit $rc"; }
run "$CALBENCH" station run --plan "$SRC/tests/data/short_plan.toml" --emulated --db s.db --out run9 --operator ""
[ "$rc" = 2 ] && grep -q -- "--operator: operator name .. must be 1 to 64 characters" err.txt || { cat err.txt; fail "empty --operator for a station: exit $rc"; }
# Issue 35 tryout: names that look like the storer's. Invisible characters and a Cyrillic letter among
# Latin ones are bad input (exit 2, naming the option and the code point); a no-break space is a space,
# so the same person (four-eyes, exit 1). Nothing is approved by any of them.
run "$CALBENCH" db approve 1 --operator "$(printf 'Sam\xe2\x80\x8b Station')"
[ "$rc" = 2 ] && grep -q -- "--operator: operator name .* contains the invisible or format character U+200B" err.txt || { cat err.txt; fail "zero-width space in a name: exit $rc"; }
run "$CALBENCH" db approve 1 --operator "$(printf 'Sam Station\xe2\x80\x8b')"
[ "$rc" = 2 ] && grep -q -- "--operator: operator name .* contains the invisible or format character U+200B" err.txt || { cat err.txt; fail "trailing zero-width space: exit $rc"; }
run "$CALBENCH" db approve 1 --operator "Sаm Station"  # Cyrillic а (U+0430)
[ "$rc" = 2 ] && grep -q -- "--operator: operator name .* mixes Latin and Cyrillic letters in the word 'Sаm' (U+0430)" err.txt || { cat err.txt; fail "mixed-script name: exit $rc"; }
run env CALBENCH_OPERATOR="$(printf 'Sam\xc2\xadStation')" "$CALBENCH" db approve 1
[ "$rc" = 2 ] && grep -q "CALBENCH_OPERATOR: operator name .* U+00AD" err.txt || { cat err.txt; fail "soft hyphen in CALBENCH_OPERATOR: exit $rc"; }
run "$CALBENCH" db approve 1 --operator "$(printf 'Sam\xc2\xa0Station')"
[ "$rc" = 1 ] && grep -q "four-eyes: set 1 was stored by 'Sam Station'" err.txt || { cat err.txt; fail "no-break space taken for another person: exit $rc"; }
run "$CALBENCH" db approve 1 --operator "$(printf 'Sam\xffStation')"
[ "$rc" = 2 ] && LC_ALL=C grep -aq -- "--operator: operator name .* is not valid UTF-8" err.txt || { cat err.txt; fail "invalid UTF-8 name: exit $rc"; }
[ "$(sqlite3 s.db "SELECT status FROM coefficient_sets WHERE id = 1")" = draft ] || fail "a look-alike name approved the set"
# Another, named operator signs: approved; the audit log names signer and storer.
"$CALBENCH" db approve 1 --operator "Quinn QC" > out.txt || { cat out.txt; fail "signed approval refused"; }
"$CALBENCH" db history 1001 > hist.txt
me=$(id -un)
grep -q "Quinn QC@line-7  coefficient_set 1  status  draft -> approved: signed by Quinn QC (--operator; OS user $me, not authenticated (SQLite)), stored by Sam Station (OS user $me, not authenticated (SQLite))" hist.txt \
  || { cat hist.txt; fail "approval signature not in the history"; }
# Issue 35: the OS user is recorded beside the typed name, and said to be unauthenticated.
[ "$(sqlite3 s.db "SELECT db_role FROM audit_log WHERE entity_id = 1 AND action = 'status'")" = "$me" ] || fail "OS user not recorded"
[ "$(sqlite3 s.db "SELECT created_by_role FROM coefficient_sets WHERE id = 1")" = "$me" ] || fail "creator's OS user not recorded"
grep -q "draft -> approved.*\[OS user $me, not authenticated (SQLite)\]" hist.txt || { cat hist.txt; fail "history without the OS user"; }
"$CALBENCH" db history 1001 --json | python3 -c '
import json, sys
h = json.load(sys.stdin)
assert h["authenticated"] is False, h
sig = [e for e in h["history"] if e["action"] == "status"][0]
assert sig["login"] == sys.argv[1] and sig["name"] == "Quinn QC" and sig["authenticated"] is False, sig
run = [e for e in h["history"] if e["entity"] == "bench_run"][0]["recording"]
assert run["uri"].startswith("file://") and run["uri"].endswith("/run/recording"), run
assert len(run["digest_sha256"]) == 64, run' "$me" || fail "history --json without login, name or recording"
grep -q "approve-refused  four-eyes" hist.txt || fail "four-eyes refusal not in the history"

# Settings: changing needs a named operator; unknown keys/values are bad input; audited with name and time.
run "$CALBENCH" db settings four_eyes off
[ "$rc" = 1 ] && grep -q "changing a setting needs a named operator" err.txt || { cat err.txt; fail "unsigned setting change: exit $rc"; }
run "$CALBENCH" db settings four_eyes maybe --operator "Quinn QC"
[ "$rc" = 2 ] && grep -q "four_eyes: 'maybe' is not one of: on, off" err.txt || { cat err.txt; fail "bad setting value: exit $rc"; }
run "$CALBENCH" db settings five_eyes on --operator "Quinn QC"
[ "$rc" = 2 ] && grep -q "unknown setting 'five_eyes' (settings: four_eyes)" err.txt || { cat err.txt; fail "unknown setting: exit $rc"; }
"$CALBENCH" db settings | grep -q "four_eyes = on  (built-in default)" || fail "default setting"
# A one-person lab: the same operator stores and approves once four_eyes is off.
CALBENCH_OPERATOR="Olga Solo" "$CALBENCH" db store-bench --coeffs run/COEFFS.json --recording run/recording \
  --qc residual=0.1:1 > /dev/null
run "$CALBENCH" db approve 2 --operator "Olga Solo"
[ "$rc" = 1 ] || fail "self-approval with four_eyes on: exit $rc"
"$CALBENCH" db settings four_eyes off --operator "Olga Solo" > /dev/null
"$CALBENCH" db settings --json | python3 -c '
import json, sys
s = json.load(sys.stdin)["settings"][0]
assert s["key"] == "four_eyes" and s["value"] == "off" and not s["default"], s
assert s["changed_by"] == "Olga Solo@line-7" and s["changed_at"], s'
"$CALBENCH" db approve 2 --operator "Olga Solo" > out.txt || { cat err.txt; fail "one-person lab approval refused"; }
grep -q "four-eyes off" <("$CALBENCH" db history 1001) || fail "relaxed approval not marked in the history"

# Four-eyes compares names ignoring case and spacing (issue 35): Tess stores, "tess" and "TESS  tuck"-like
# variants are the same person and are refused; the status stays draft.
CALBENCH_OPERATOR="Tess  Tuck" "$CALBENCH" db store-bench --coeffs run/COEFFS.json --recording run/recording \
  --qc residual=0.1:1 > /dev/null
"$CALBENCH" db settings four_eyes on --operator "Olga Solo" > /dev/null
for who in "tess tuck" "TESS TUCK" "Tess   tuck"; do
  run "$CALBENCH" db approve 3 --operator "$who"
  [ "$rc" = 1 ] && grep -q "four-eyes: set 3 was stored by 'Tess  Tuck'" err.txt || { cat err.txt; fail "'$who' approved Tess Tuck's set: exit $rc"; }
done
[ "$(sqlite3 s.db "SELECT status FROM coefficient_sets WHERE id = 3")" = draft ] || fail "a case variant approved"
# The recording: an absolute file:// URI naming this host, and the digest of all its files.
row=$(sqlite3 s.db "SELECT recording_uri || ' ' || recording_digest FROM bench_runs ORDER BY id DESC LIMIT 1")
[ "$row" = "file://$(hostname)$T/run/recording $(python3 "$SRC/tests/support/folder_digest.py" run/recording)" ] || fail "recording uri/digest: $row"

# Provisioning records its operator.
"$CALBENCH" provision 1001 --set 2 --export p.json --operator "Pat Provisioning" > /dev/null
[ "$(sqlite3 s.db "SELECT actor FROM provisioning_events ORDER BY id DESC LIMIT 1")" = "Pat Provisioning@line-7" ] || fail "provisioning actor"

# An aborted run is in the history, with its reason and the partial recording.
run "$CALBENCH" station run --plan "$SRC/tests/data/short_plan.toml" --emulated --db s.db --out run2 \
  --inject table-kill-at=20 --operator "Sam Station"
[ "$rc" = 1 ] && grep -q "recorded as aborted bench run 4 in s.db" err.txt || { cat err.txt; fail "aborted run: exit $rc"; }
"$CALBENCH" db history 1001 > hist.txt
grep -q "Sam Station@line-7  bench_run 4  create  plan short, outcome aborted: .*; partial recording run2/recording" hist.txt \
  || { cat hist.txt; fail "aborted run not in the history"; }
[ "$(sqlite3 s.db "SELECT count(*) FROM coefficient_sets")" = 3 ] || fail "an aborted run created a set"

# The device report shows the names.
"$CALBENCH" report 1001 --html r.html > /dev/null
grep -q "Quinn QC@line-7" r.html && grep -q "Pat Provisioning@line-7" r.html && grep -q "Sam Station@line-7" r.html \
  || fail "report without the operators' names"
grep -q "Quinn QC@line-7 (OS user $me, not authenticated (SQLite))" r.html || fail "report does not say the signature is unauthenticated"
# A status changed by hand in the file (no signed approval in the audit log) is not a PASS (issue 35).
# Issue 54: the store refuses it (an approval is made with its signed audit row) ...
if sqlite3 s.db "UPDATE coefficient_sets SET status = 'approved' WHERE id = 3" 2> upd.txt; then fail "a status changed by hand"; fi
grep -q "an approval is made with its signed audit row" upd.txt || { cat upd.txt; fail "hand approval refused for another reason"; }
# ... and one who writes the file and drops that rule still gets no PASS.
sqlite3 s.db "DROP TRIGGER coefficient_sets_approval_signed; UPDATE coefficient_sets SET status = 'approved' WHERE id = 3"
"$CALBENCH" report 1001 --html r2.html > /dev/null
grep -q 'data-verdict="FAIL"' r2.html && grep -q "set 3 is approved but the audit log holds no signed approval of set 3" r2.html \
  || fail "a hand-made approval passed the report"
# The IMU digest names the file it is of (issue 35 sign-off: an HDF5 recording's was called "SHA-256
# of imu.csv" although it is of recording.h5): history text and --json, and the device report.
"$CALBENCH" convert run/recording --to h5 --out rech5 > /dev/null
rm -f h.db
for rec in run/recording rech5; do
  CALBENCH_OPERATOR="Olga Solo" "$CALBENCH" db store-bench --db h.db --coeffs run/COEFFS.json --recording "$rec" \
    --qc residual=0.1:1 > /dev/null
done
"$CALBENCH" db history 1001 --db h.db > hist.txt
csv_sum=$(sha256sum run/recording/imu.csv | cut -d' ' -f1); h5_sum=$(sha256sum rech5/recording.h5 | cut -d' ' -f1)
grep -q "^    SHA-256 of imu.csv $csv_sum$" hist.txt && grep -q "^    SHA-256 of recording.h5 $h5_sum$" hist.txt \
  || { cat hist.txt; fail "history does not name the hashed IMU file"; }
"$CALBENCH" db history 1001 --db h.db --json | python3 -c '
import json, sys
runs = [e["recording"] for e in json.load(sys.stdin)["history"] if e["entity"] == "bench_run"]
got = sorted((r["imu_table_file"], r["imu_csv_sha256"]) for r in runs)
assert got == sorted([("imu.csv", sys.argv[1]), ("recording.h5", sys.argv[2])]), got' "$csv_sum" "$h5_sum" \
  || fail "history --json does not name the hashed IMU file"
"$CALBENCH" report 1001 --db h.db --html h.html > /dev/null
grep -q "SHA-256 of recording.h5" h.html && grep -q "SHA-256 of imu.csv" h.html || fail "report does not name the hashed IMU file"
# Moved away: the file cannot be told, and the report says so instead of guessing.
mv rech5 gone && "$CALBENCH" db history 1001 --db h.db > hist.txt
grep -q "^    SHA-256 of the IMU table's file (imu.csv, or recording.h5 for an HDF5 recording) $h5_sum$" hist.txt \
  || { cat hist.txt; fail "history guesses the file of a recording not at hand"; }
echo "db_signatures: ok"
