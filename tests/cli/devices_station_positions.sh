#!/usr/bin/env bash
# A positions plan ([plan] kind = "positions", bench/plans/multipos.toml) on the emulated
# position-only table (issue 37):
#  - two emulated units: one multipos recording each (meta.json kind multipos with site, imu.csv SI,
#    no reference.csv), complete and read back; in the data each of the 18 poses is static (|accel|
#    ≈ g, gyro ≈ 0 but for its bias) and the moves between them turn; each unit fitted by the
#    multi-position estimator (COEFFS.json with its "multipos" key) and stored with --db: the
#    coefficients within 3σ of the emulated unit's truth (expressed in the fit's frame);
#  - a rate step in a positions plan is refused naming file, line and field (exit 2);
#  - `calbench emulate table --position-only` refuses a write selecting rate mode (Modbus exception 3)
#    and accepts position mode;
#  - Ctrl-C mid-plan: the table is stopped and disabled, the captured recording kept (incomplete).
set -euo pipefail
tmp=$(mktemp -d)
emu_pid=
trap '[ -n "$emu_pid" ] && kill "$emu_pid" 2>/dev/null; rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# The shipped plan with shorter dwells (the poses and moves as shipped).
sed 's/^dwell_s = .*/dwell_s = 1.5/' "$SRC/bench/plans/multipos.toml" >"$tmp/plan.toml"
set +e
"$CALBENCH" station run --plan "$tmp/plan.toml" --emulated --units 2 --out "$tmp/run" --db "$tmp/s.db" --json >"$tmp/run.json" 2>"$tmp/run.log"
rc=$?
set -e
[ "$rc" = 0 ] || { cat "$tmp/run.log" "$tmp/run.json"; fail "positions plan: exit $rc"; }
python3 - "$tmp/run" "$tmp/plan.toml" <<'PY'
import csv, json, math, os, sys
run, plan = sys.argv[1], sys.argv[2]
poses = sum(1 for l in open(plan) if l.strip() == "[[step]]")
slots = sorted(d for d in os.listdir(run) if os.path.isdir(os.path.join(run, d)))
assert len(slots) == 2, slots
for s in slots:
    rec = os.path.join(run, s, "recording")
    meta = json.load(open(os.path.join(rec, "meta.json")))
    assert meta["kind"] == "multipos", meta["kind"]
    assert meta.get("status") == "complete", "recording not complete"
    assert abs(meta["site"]["lat_deg"] - 55.75) < 1e-9 and "h_m" in meta["site"], meta["site"]
    assert not os.path.exists(os.path.join(rec, "reference.csv")), "a multipos recording has no reference.csv"
    c = json.load(open(os.path.join(run, s, "COEFFS.json")))
    truth = json.load(open(os.path.join(run, s, "EMULATED_TRUTH.json")))
    m = c["multipos"]
    assert m["g_spread_m_s2"] < 0.2 * m["g_spread_raw_m_s2"], (m["g_spread_raw_m_s2"], m["g_spread_m_s2"])
    # The truth in the fit's frame (x along the accelerometer x axis, y in its x-y plane): (I + M_a) = L·Q
    # with L lower triangular, and the gyros (I + M_g)·Qᵀ — Gram–Schmidt on the rows of (I + M_a).
    A = [[(1.0 if i == j else 0.0) + truth["accel"]["M"][i][j] for j in range(3)] for i in range(3)]
    Q = []
    for i in range(3):
        v = A[i][:]
        for q in Q:
            d = sum(a * b for a, b in zip(A[i], q))
            v = [a - d * b for a, b in zip(v, q)]
        n = math.sqrt(sum(a * a for a in v))
        Q.append([a / n for a in v])
    L = [[sum(A[i][k] * Q[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    G = [[(1.0 if i == j else 0.0) + truth["gyro"]["M"][i][j] for j in range(3)] for i in range(3)]
    GQt = [[sum(G[i][k] * Q[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    within = total = 0
    worst = (0, "")
    for name, Mt in (("accel", [[L[i][j] - (i == j) for j in range(3)] for i in range(3)]),
                     ("gyro", [[GQt[i][j] - (i == j) for j in range(3)] for i in range(3)])):
        e = c[name]
        pairs = [(e["bias"][i], truth[name]["bias"][i], e["sigma_bias"][i], f"{name}.bias[{i}]") for i in range(3)]
        pairs += [(e["M"][i][j], Mt[i][j], e["sigma_M"][i][j], f"{name}.M[{i}][{j}]") for i in range(3) for j in range(3)
                  if not (name == "accel" and j > i)]
        for est, tru, sig, what in pairs:
            z = abs(est - tru) / sig
            total += 1
            within += z <= 3
            worst = max(worst, (z, what))
    assert within >= 0.9 * total, (s, within, total, worst)
    print(f"slot {s}: {within}/{total} coefficients within 3σ of the truth (worst {worst[1]} {worst[0]:.1f}σ)")
    rows = [r for r in csv.reader(l for l in open(os.path.join(rec, "imu.csv")) if not l.startswith("#"))]
    head, rows = rows[0], [[float(x) for x in r] for r in rows[1:]]
    c = {k: head.index(k) for k in head}
    t = [r[c["t_s"]] for r in rows]
    assert all(b > a for a, b in zip(t, t[1:])), "time not increasing"
    rate = (len(t) - 1) / (t[-1] - t[0])
    assert abs(rate - meta["imu_rate_hz"]) < 0.01 * meta["imu_rate_hz"], (rate, meta["imu_rate_hz"])
    # Windows of 0.25 s: static (|mean f| ≈ g within 5 %: the emulated units are uncalibrated, their
    # scale factors and biases move |f| by up to ~3.5 % between poses; |mean ω| < 0.02 rad/s, gyro
    # bias included) or turning (|ω| > 0.2 rad/s; the plan moves at 30 °/s = 0.52 rad/s).
    n = int(0.25 * rate)
    kinds = []
    for i in range(0, len(rows) - n, n):
        w = rows[i:i + n]
        f = [sum(r[c[k]] for r in w) / n for k in ("ax_m_s2", "ay_m_s2", "az_m_s2")]
        g = [sum(r[c[k]] for r in w) / n for k in ("gx_rad_s", "gy_rad_s", "gz_rad_s")]
        fn, gn = math.sqrt(sum(x * x for x in f)), math.sqrt(sum(x * x for x in g))
        kinds.append("S" if abs(fn - 9.8152) < 0.05 * 9.8152 and gn < 0.02 else "M" if gn > 0.2 else "?")
    segs = "".join(kinds)
    static_runs = [r for r in segs.replace("?", "M").split("M") if len(r) >= 4]  # ≥ 1 s static
    assert len(static_runs) == poses, (s, len(static_runs), poses, segs)
    assert segs.count("M") >= 20, ("no moves recorded between the poses", segs)
    print(f"slot {s}: {len(rows)} samples, {len(static_runs)} static poses, {segs.count('M')} turning windows")
PY
# Both sets stored as drafts.
"$CALBENCH" db devices --db "$tmp/s.db" | grep -c "draft" | grep -qx 2 || { "$CALBENCH" db devices --db "$tmp/s.db"; fail "two draft sets expected in the store"; }

# A rate step in a positions plan: refused, file, line and field named, nothing run.
cat "$tmp/plan.toml" >"$tmp/bad.toml"
cat >>"$tmp/bad.toml" <<'TOML'

[[step]]
kind = "rate"
axis = "z"
rate_dps = 20.0
dwell_s = 2.0
TOML
line=$(grep -n '^kind = "rate"' "$tmp/bad.toml" | cut -d: -f1)
set +e
"$CALBENCH" station run --plan "$tmp/bad.toml" --emulated --out "$tmp/bad" >"$tmp/bad.out" 2>&1
rc=$?
set -e
[ "$rc" = 2 ] || { cat "$tmp/bad.out"; fail "rate step in a positions plan: exit $rc, expected 2"; }
grep -q "bad.toml" "$tmp/bad.out" && grep -q "$line" "$tmp/bad.out" && grep -q "step\[19\].kind" "$tmp/bad.out" &&
  grep -q "positions plan" "$tmp/bad.out" || { cat "$tmp/bad.out"; fail "the refusal does not name file, line $line and field"; }
[ ! -e "$tmp/bad" ] || fail "something was written for a refused plan"

# The emulated position-only table refuses rate mode (a raw Modbus TCP client).
"$CALBENCH" emulate table --position-only --listen 127.0.0.1:0 --port-file "$tmp/port" >"$tmp/emu.log" 2>&1 &
emu_pid=$!
for _ in $(seq 100); do [ -s "$tmp/port" ] && break; sleep 0.05; done
[ -s "$tmp/port" ] || fail "table emulator did not start"
python3 - "$(cat "$tmp/port")" <<'PY'
import socket, struct, sys
s = socket.create_connection(("127.0.0.1", int(sys.argv[1])), timeout=5)
def req(tid, pdu):
    s.sendall(struct.pack(">HHHB", tid, 0, len(pdu) + 1, 1) + pdu)
    h = s.recv(7); _, _, n, _ = struct.unpack(">HHHB", h)
    body = b""
    while len(body) < n - 1: body += s.recv(n - 1 - len(body))
    return body
MODE = 0x0101  # inner axis MODE_OF_OPERATION (docs/devices.md register map)
r = req(1, struct.pack(">BHHBH", 0x10, MODE, 1, 2, 3))   # write multiple: rate mode
assert r[0] == 0x90 and r[1] == 3, ("rate mode not refused", r)
r = req(2, struct.pack(">BHH", 0x06, MODE - 0x0100, 3))  # write single, outer axis: rate mode
assert r[0] == 0x86 and r[1] == 3, ("rate mode not refused", r)
r = req(3, struct.pack(">BHH", 0x03, MODE, 1))           # nothing was changed
assert r[0] == 0x03 and struct.unpack(">H", r[2:4])[0] != 3, r
r = req(4, struct.pack(">BHHBH", 0x10, MODE, 1, 2, 1))   # position mode: accepted
assert r[0] == 0x10, ("position mode refused", r)
r = req(5, struct.pack(">BHH", 0x03, MODE, 1))
assert struct.unpack(">H", r[2:4])[0] == 1, r
print("position-only table: rate mode refused (exception 3), position mode accepted")
PY
kill "$emu_pid"; wait "$emu_pid" 2>/dev/null || true; emu_pid=

# Ctrl-C mid-plan: the table stopped, the captured recording kept (incomplete).
sed 's/^dwell_s = .*/dwell_s = 30.0/' "$SRC/bench/plans/multipos.toml" >"$tmp/long.toml"
"$CALBENCH" station run --plan "$tmp/long.toml" --emulated --out "$tmp/abort" --json >"$tmp/abort.json" 2>"$tmp/abort.log" &
pid=$!
for _ in $(seq 600); do
  [ -f "$tmp/abort/recording/imu.csv" ] && [ "$(wc -l <"$tmp/abort/recording/imu.csv")" -gt 20000 ] && break
  sleep 0.1
done
kill -INT "$pid"
set +e
wait "$pid"
rc=$?
set -e
[ "$rc" != 0 ] || fail "an interrupted run exited 0"
python3 - "$tmp/abort" <<'PY'
import json, sys, os
d = sys.argv[1]
j = json.load(open(d + ".json"))
assert j["aborted"] is True and j["table_stopped"] is True, j
assert "interrupted" in j["message"] and "table stopped and disabled" in j["message"], j["message"]
meta = json.load(open(os.path.join(d, "recording", "meta.json")))
assert meta["kind"] == "multipos" and meta.get("status") == "incomplete", meta
n = sum(1 for l in open(os.path.join(d, "recording", "imu.csv")) if l[0].isdigit() or l[0] == "-")
assert n > 20000, n
assert not os.path.exists(os.path.join(d, "reference.csv")) and not os.path.exists(os.path.join(d, "COEFFS.json"))  # aborted: not fitted
print(f"aborted: table stopped, {n} samples kept")
PY
echo "OK"
