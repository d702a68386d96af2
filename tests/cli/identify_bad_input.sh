#!/usr/bin/env bash
# calbench identify: bad inputs end with status 2 and a message naming file, line and column.
set -euo pipefail
: "${CALBENCH:?}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

expect_error() {  # file, expected substring(s) of the message...
  local f=$1; shift
  local rc=0
  "$CALBENCH" identify "$f" --json > "$tmp/out" 2> "$tmp/err" || rc=$?
  [ "$rc" -eq 2 ] || fail "$f: exit status $rc, expected 2 ($(cat "$tmp/err"))"
  for s in "$@"; do grep -qF -- "$s" "$tmp/err" || fail "$f: message lacks '$s': $(cat "$tmp/err")"; done
}

# Too short.
{ echo "t_s,x"; for i in $(seq 0 9); do echo "$i,$((i % 3))"; done; } > "$tmp/short.csv"
expect_error "$tmp/short.csv" "short.csv" "too short"

# Constant column.
{ echo "t_s,x"; for i in $(seq 0 199); do echo "$i,4.5"; done; } > "$tmp/const.csv"
expect_error "$tmp/const.csv" "const.csv" "'x'" "constant"

# NaN on line 52 (header is line 1).
{ echo "t_s,x"; for i in $(seq 0 199); do if [ "$i" -eq 50 ]; then echo "$i,nan"; else echo "$i,$(( (i * 7919) % 13 ))"; fi; done; } > "$tmp/nan.csv"
expect_error "$tmp/nan.csv" "nan.csv:52" "'x'"

# Gap: sample t = 100 missing, detected at the row t = 101 (line 102: header is line 1, t = 0 line 2).
{ echo "t_s,x"; for i in $(seq 0 199); do [ "$i" -eq 100 ] && continue; echo "$i,$(( (i * 7919) % 13 ))"; done; } > "$tmp/gap.csv"
expect_error "$tmp/gap.csv" "gap.csv:102" "'t_s'" "gap"

# Irregular step.
{ echo "t_s,x"; for i in $(seq 0 199); do if [ "$i" -eq 80 ]; then echo "79.5,1"; else echo "$i,$(( (i * 7919) % 13 ))"; fi; done; } > "$tmp/irr.csv"
expect_error "$tmp/irr.csv" "irr.csv:82" "'t_s'"

# Missing column, no t_s.
{ echo "t_s,x"; for i in $(seq 0 199); do echo "$i,$(( (i * 7919) % 13 ))"; done; } > "$tmp/ok.csv"
rc=0; "$CALBENCH" identify "$tmp/ok.csv" --column nosuch 2> "$tmp/err" > /dev/null || rc=$?
[ "$rc" -eq 2 ] && grep -qF "'nosuch'" "$tmp/err" || fail "missing column: $rc $(cat "$tmp/err")"
{ echo "time,x"; for i in $(seq 0 199); do echo "$i,$i"; done; } > "$tmp/not.csv"
expect_error "$tmp/not.csv" "not.csv" "'t_s'"

# Non-existent input: CLI11 rejects it with status 2 too.
rc=0; "$CALBENCH" identify "$tmp/none.csv" 2>/dev/null >/dev/null || rc=$?
[ "$rc" -ne 0 ] || fail "missing file accepted"
echo OK
