#!/usr/bin/env bash
# calbench emulate table: binds loopback on an ephemeral port, accepts TCP connections, rejects bad
# options with exit status 2, stops cleanly on SIGTERM.
set -euo pipefail
tmp=$(mktemp -d)
pid=""
cleanup() { [ -n "$pid" ] && kill -9 "$pid" 2>/dev/null || true; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$CALBENCH" emulate table --listen 127.0.0.1:0 --port-file "$tmp/port" --watchdog 0.2 >"$tmp/out" 2>&1 &
pid=$!
for _ in $(seq 1 100); do [ -s "$tmp/port" ] && break; sleep 0.05; done
[ -s "$tmp/port" ] || fail "no port file"
port=$(cat "$tmp/port")
[ "$port" -gt 0 ] || fail "bad port $port"
grep -q "listening on modbus-tcp://127.0.0.1:$port" "$tmp/out" || fail "no listening line: $(cat "$tmp/out")"
# A TCP connection to the port succeeds (bash /dev/tcp).
exec 3<>"/dev/tcp/127.0.0.1/$port" || fail "cannot connect to $port"
# FC03 read of STATUSWORD (axis 0, address 16, 1 register), MBAP transaction 1, unit 1.
printf '\x00\x01\x00\x00\x00\x06\x01\x03\x00\x10\x00\x01' >&3
reply=$(timeout 2 head -c 11 <&3 | od -An -tx1 | tr -d ' \n')
exec 3>&-
[ "${reply:0:18}" = "000100000005010302" ] || fail "unexpected Modbus reply '$reply'"
kill -TERM "$pid"
wait "$pid" || fail "emulator exit status $?"
pid=""
grep -q "stopped" "$tmp/out" || fail "no stop message"

set +e
"$CALBENCH" emulate table --listen nonsense >/dev/null 2>"$tmp/err"; rc=$?
set -e
[ "$rc" -eq 2 ] || fail "bad --listen: exit $rc"
grep -q "listen" "$tmp/err" || fail "error does not name the option"
set +e
"$CALBENCH" emulate table --order badc >/dev/null 2>"$tmp/err"; rc=$?
set -e
[ "$rc" -eq 2 ] || fail "bad --order: exit $rc"
echo "ok"
