#!/usr/bin/env bash
# Operator prompts of a plan (issue 38; docs/devices.md "Live view and operator prompts"), the paths
# the browser test does not take:
#  - without --db, on the terminal: "y" confirms and the run completes; a line rejects (the run
#    aborts naming the line, the table stopped); a closed standard input rejects;
#  - with --db, a prompt nobody answers times out: the run aborts (exit 1, "not answered within"),
#    the prompt is 'timed out' in the store, the slot's progress row 'aborted' with the reason, and
#    the question and its end are in the audit log;
#  - a prompt step with a bad field is bad input naming the file, line and field (exit 2).
set -euo pipefail
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
plan() {  # plan TIMEOUT_S [EXTRA_PROMPT_LINE]: the shared prompt plan with this timeout (and line)
  sed -e "s/^timeout_s = .*/timeout_s = $1/" -e "s/^slot = \"1\"/slot = \"1\"\n${2:-}/" "$SRC/tests/data/prompt_plan.toml"
}
plan 30 > "$tmp/p30.toml"
plan 1 > "$tmp/p1.toml"
run() { "$CALBENCH" station run --emulated --plan "$1" --out "$tmp/$2" "${@:3}"; }

# Terminal: confirmed.
echo y | run "$tmp/p30.toml" yes > "$tmp/yes.log" 2>&1 || { cat "$tmp/yes.log"; fail "a confirmed prompt did not complete the run"; }
grep -q "operator prompt (slot 1): turn the fixture's clamp in slot 1, then confirm" "$tmp/yes.log" || fail "the prompt was not asked"
[ -f "$tmp/yes/COEFFS.json" ] || fail "no coefficients after a confirmed prompt"

# Terminal: rejected with a reason; the run aborts, the table stopped.
set +e
echo "cable broken" | run "$tmp/p30.toml" no > "$tmp/no.log" 2>&1; rc=$?
set -e
[ "$rc" = 1 ] || { cat "$tmp/no.log"; fail "a rejected prompt: exit $rc, expected 1"; }
grep -q "rejected at the terminal: cable broken" "$tmp/no.log" || { cat "$tmp/no.log"; fail "the rejection's reason not given"; }
grep -q "table stopped and disabled" "$tmp/no.log" || fail "the table was not stopped after a rejection"
[ ! -f "$tmp/no/COEFFS.json" ] || fail "coefficients written after a rejected prompt"

# Terminal: standard input closed.
set +e
run "$tmp/p30.toml" closed < /dev/null > "$tmp/closed.log" 2>&1; rc=$?
set -e
[ "$rc" = 1 ] && grep -q "standard input closed" "$tmp/closed.log" || { cat "$tmp/closed.log"; fail "closed stdin: exit $rc"; }

# Store: nobody answers within 1 s.
set +e
run "$tmp/p1.toml" timeout --db "$tmp/s.db" < /dev/null > "$tmp/timeout.log" 2>&1; rc=$?
set -e
[ "$rc" = 1 ] && grep -q "not answered within 1 s" "$tmp/timeout.log" || { cat "$tmp/timeout.log"; fail "timeout: exit $rc"; }
python3 - "$tmp/s.db" <<'PY' || fail "the store after a timed-out prompt"
import sqlite3, sys
c = sqlite3.connect(sys.argv[1])
p = c.execute("SELECT state, reason, answered_by FROM station_prompts").fetchall()
assert p == [("timed out", "not answered within 1 s", "station")], p
r = c.execute("SELECT state, reason, step_kind FROM station_progress").fetchall()
assert len(r) == 1 and r[0][0] == "aborted" and "not answered within 1 s" in r[0][1], r
a = [x[0] for x in c.execute("SELECT action FROM audit_log WHERE entity = 'station_prompt' ORDER BY id")]
assert a == ["ask", "timeout"], a
PY

# Bad input: an empty text, an unknown key.
plan 30 > "$tmp/bad1.toml"; sed -i 's/^text = .*/text = ""/' "$tmp/bad1.toml"
plan 30 'colour = "red"' > "$tmp/bad2.toml"
for b in bad1 bad2; do
  set +e
  run "$tmp/$b.toml" "$b" > "$tmp/$b.log" 2>&1; rc=$?
  set -e
  [ "$rc" = 2 ] && grep -q "$b.toml" "$tmp/$b.log" && grep -qE "step\[2\]\.(text|colour)" "$tmp/$b.log" ||
    { cat "$tmp/$b.log"; fail "$b: exit $rc, expected 2 naming the file and the field"; }
done
# Enter alone asks again (it never aborts a run); a CR LF "y" confirms.
printf '\n\r\ny\r\n' | run "$tmp/p30.toml" enter > "$tmp/enter.log" 2>&1 || { cat "$tmp/enter.log"; fail "an empty line aborted the run"; }
# A prompt about a slot the fixture lacks, a prompt text with a control character or only spaces,
# --pace with an external table: bad input before anything moves.
set +e
sed 's/^slot = .*/slot = "9"/' "$tmp/p30.toml" > "$tmp/s9.toml"
run "$tmp/s9.toml" slot9 --units 2 > /dev/null 2> "$tmp/slot.log"; rc1=$?
sed 's/^text = .*/text = "ring\\u0007 the bell"/' "$tmp/p30.toml" > "$tmp/bell.toml"
run "$tmp/bell.toml" bell > /dev/null 2> "$tmp/bell.log"; rc2=$?
sed 's/^text = .*/text = "   "/' "$tmp/p30.toml" > "$tmp/blank.toml"
run "$tmp/blank.toml" blank > /dev/null 2> "$tmp/blank.log"; rc3=$?
run "$tmp/p30.toml" pace --pace 1 --table modbus-tcp://127.0.0.1:9 > /dev/null 2> "$tmp/pace.log"; rc4=$?
set -e
[ "$rc1" = 2 ] && grep -q "s9.toml:" "$tmp/slot.log" && grep -q "slot '9'" "$tmp/slot.log" ||
  { cat "$tmp/slot.log"; fail "a prompt naming no slot of the fixture: exit $rc1"; }
[ "$rc2" = 2 ] && grep -q "control character" "$tmp/bell.log" || { cat "$tmp/bell.log"; fail "a control character: exit $rc2"; }
[ "$rc3" = 2 ] && grep -q "only spaces" "$tmp/blank.log" || { cat "$tmp/blank.log"; fail "a blank text: exit $rc3"; }
[ "$rc4" = 2 ] && grep -q -- "--pace" "$tmp/pace.log" || { cat "$tmp/pace.log"; fail "--pace with --table: exit $rc4"; }
[ ! -e "$tmp/slot9/recording" ] || fail "the table moved for a bad prompt slot"
echo "station_prompts: ok"
