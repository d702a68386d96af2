#!/usr/bin/env bash
# Station killed with SIGKILL while the table spins → the (external) emulated table comes to rest by
# itself within its watchdog period plus the deceleration time, with fault 5 (communication loss).
# Then Ctrl-C (SIGINT) while spinning → the station itself stops and disables the table (no fault),
# exits 1 with "interrupted", and leaves an incomplete recording.
set -euo pipefail
tmp=$(mktemp -d)
emu=""; st=""
cleanup() { for p in $st $emu; do kill -9 "$p" 2>/dev/null || true; done; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
cat >"$tmp/plan.toml" <<'TOML'
[plan]
name = "spin"
[site]
lat_deg = 55.75
lon_deg = 37.62
h_m = 150.0
[table]
max_rate_dps = 500.0
max_accel_dps2 = 200.0
slew_rate_dps = 60.0
settle_s = 0.2
remount_s = 1.0
rate_accuracy_ppm = 1.0
position_accuracy_arcsec = 2.0
axis_wobble_arcsec = 1.0
[[step]]
kind = "rate"
axis = "z"
rate_dps = 50.0
dwell_s = 60.0
label = "+50 dps about z"
TOML
"$CALBENCH" emulate table --listen 127.0.0.1:0 --port-file "$tmp/port" --watchdog 0.3 >"$tmp/emu.log" 2>&1 &
emu=$!
for _ in $(seq 1 100); do [ -s "$tmp/port" ] && break; sleep 0.05; done
port=$(cat "$tmp/port")
"$CALBENCH" station run --plan "$tmp/plan.toml" --table "modbus-tcp://127.0.0.1:$port" --emulated \
  --out "$tmp/out" >"$tmp/st.log" 2>&1 &
st=$!
python3 - "$port" "$st" <<'PY' || { cat "$tmp/st.log" >&2; fail "watchdog did not stop the table"; }
import os, signal, socket, struct, sys, time
port, pid = int(sys.argv[1]), int(sys.argv[2])
tid = 0
def axis1():
    global tid
    tid += 1
    s = socket.create_connection(("127.0.0.1", port), timeout=1)
    s.sendall(struct.pack(">HHHBBHH", tid, 0, 6, 1, 3, 0x0110, 8))  # FC03 axis 1, registers 16..23
    data = b""
    while len(data) < 9 + 16:
        chunk = s.recv(64)
        if not chunk: break
        data += chunk
    s.close()
    regs = struct.unpack(">8H", data[9:25])
    rate = struct.unpack(">f", struct.pack(">HH", regs[6], regs[7]))[0]
    return regs[0], regs[2], rate   # statusword, fault code, ACT_RATE (deg/s, abcd)
t_end = time.time() + 20
while True:
    sw, fault, rate = axis1()
    if abs(rate - 50.0) < 0.01: break
    if time.time() > t_end: sys.exit("table never reached 50 deg/s (rate %.3f)" % rate)
    time.sleep(0.02)
time.sleep(0.3)
os.kill(pid, signal.SIGKILL)
t_kill = time.time()
while True:
    sw, fault, rate = axis1()
    if rate == 0.0 and fault == 5: break
    if time.time() - t_kill > 3: sys.exit("after 3 s: rate %.3f fault %d" % (rate, fault))
    time.sleep(0.01)
dt = time.time() - t_kill
# watchdog 0.3 s + 50/200 s deceleration + polling slack
assert dt < 1.2, "table at rest only %.2f s after the kill" % dt
print("table at rest %.2f s after SIGKILL, fault %d, statusword 0x%04x" % (dt, fault, sw))
PY
st=""

# Ctrl-C: the station commands stop + disable itself.
"$CALBENCH" station run --plan "$tmp/plan.toml" --table "modbus-tcp://127.0.0.1:$port" --emulated \
  --out "$tmp/out2" >"$tmp/st2.log" 2>&1 &
st=$!
python3 - "$port" "$st" <<'PY' || { cat "$tmp/st2.log" >&2; fail "Ctrl-C did not stop the table"; }
import os, signal, socket, struct, sys, time
port, pid = int(sys.argv[1]), int(sys.argv[2])
def axis1():
    s = socket.create_connection(("127.0.0.1", port), timeout=1)
    s.sendall(struct.pack(">HHHBBHH", 7, 0, 6, 1, 3, 0x0110, 8))
    data = b""
    while len(data) < 25:
        chunk = s.recv(64)
        if not chunk: break
        data += chunk
    s.close()
    regs = struct.unpack(">8H", data[9:25])
    return regs[0], regs[2], struct.unpack(">f", struct.pack(">HH", regs[6], regs[7]))[0]
t_end = time.time() + 20
while True:
    sw, fault, rate = axis1()
    if abs(rate - 50.0) < 0.01 and sw & 0x4: break
    if time.time() > t_end: sys.exit("never spinning (rate %.3f, sw 0x%04x)" % (rate, sw))
    time.sleep(0.02)
os.kill(pid, signal.SIGINT)
t0 = time.time()
while True:
    sw, fault, rate = axis1()
    if not (sw & 0x4) and rate == 0.0: break
    if time.time() - t0 > 3: sys.exit("after 3 s: rate %.3f sw 0x%04x" % (rate, sw))
    time.sleep(0.01)
assert fault in (0, 5), fault
print("Ctrl-C: disabled and at rest %.2f s after SIGINT (fault %d)" % (time.time() - t0, fault))
PY
set +e
wait "$st"; rc=$?
set -e
st=""
[ "$rc" -eq 1 ] || fail "Ctrl-C exit status $rc"
grep -q "interrupted" "$tmp/st2.log" || fail "no interrupted message: $(tail -2 "$tmp/st2.log")"
grep -q "table stopped and disabled" "$tmp/st2.log" || fail "no stop confirmation"
grep -q '"incomplete"' "$tmp/out2/recording/meta.json" || fail "recording not marked incomplete"
echo ok
