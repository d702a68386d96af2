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
echo "station_prompts: ok"
