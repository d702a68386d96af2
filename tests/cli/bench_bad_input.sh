#!/usr/bin/env bash
# Bad input: exit status 2 and a message naming file, line and field; never a crash.
set -euo pipefail
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
expect_fail() {  # expect_fail PATTERN cmd...
  local pat="$1"; shift
  set +e; "$@" > "$tmp/out" 2> "$tmp/err"; local rc=$?; set -e
  if [ $rc -ne 2 ]; then echo "expected exit 2, got $rc: $*"; cat "$tmp/err"; exit 1; fi
  if ! grep -qE "$pat" "$tmp/err"; then echo "message lacks /$pat/:"; cat "$tmp/err"; exit 1; fi
}
mkdir -p "$tmp/r"
cat > "$tmp/r/meta.json" <<'J'
{"format": "calbench-recording/1", "kind": "bench", "device": {"model": "ADIS16488A", "serial": "X"},
 "site": {"lat_deg": 50, "lon_deg": 10, "h_m": 0}, "imu_rate_hz": 100}
J
printf 't_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n0,0,0,0,0,0,-9.8\n0.01,0,0,oops,0,0,-9.8\n' > "$tmp/r/imu.csv"
printf 't_s,wx_rad_s,wy_rad_s,wz_rad_s,fx_m_s2,fy_m_s2,fz_m_s2,step\n0,0,0,0,0,0,-9.8,0\n1,0,0,0,0,0,-9.8,0\n' > "$tmp/r/reference.csv"
expect_fail "imu.csv:3: 'gz_rad_s': not a number" "$CALBENCH" fit bench "$tmp/r" --out "$tmp/c.json"
test ! -e "$tmp/c.json"
printf 't_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n0,0,0,0,0,0,-9.8\n0.01,0,0,nan,0,0,-9.8\n' > "$tmp/r/imu.csv"
expect_fail "imu.csv:3: 'gz_rad_s': NaN" "$CALBENCH" fit bench "$tmp/r"
printf 't_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n0.02,0,0,0,0,0,-9.8\n0.01,0,0,0,0,0,-9.8\n' > "$tmp/r/imu.csv"
expect_fail "imu.csv:3: 't_s': time goes backwards" "$CALBENCH" fit bench "$tmp/r"
printf 't_s,gx_rad_s,gy_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n0,0,0,0,0,-9.8\n' > "$tmp/r/imu.csv"
expect_fail "imu.csv:1: 'gz_rad_s': missing required column" "$CALBENCH" fit bench "$tmp/r"
: > "$tmp/r/imu.csv"
expect_fail "imu.csv: empty file" "$CALBENCH" fit bench "$tmp/r"
sed -i 's/"imu_rate_hz": 100//; s/"h_m": 0},/"h_m": 0}/' "$tmp/r/meta.json"
expect_fail "meta.json: 'imu_rate_hz': missing key" "$CALBENCH" fit bench "$tmp/r"
echo '{"format": "calbench-recording/1", "kind": ' > "$tmp/r/meta.json"
expect_fail "meta.json:2: invalid JSON" "$CALBENCH" fit bench "$tmp/r"
# Plans
printf '[site]\nlat_deg = 50.0\nlon_deg = 10.0\n[[step]]\nkind = "rate"\naxis = "w"\nrate_dps = 10.0\ndwell_s = 5.0\n' > "$tmp/p.toml"
expect_fail "p.toml:6: 'step\[1\].axis': expected an IMU axis" "$CALBENCH" simulate bench --plan "$tmp/p.toml" --truth random --out "$tmp/s"
printf '[site]\nlat_deg = 50.0\nlon_deg = 10.0\n[[step]]\nkind = "rate"\naxis = "xz"\nrate_dps = 10.0\ndwell_s = 5.0\n' > "$tmp/p.toml"
expect_fail "p.toml:6: 'step\[1\].axis': expected an IMU axis.*a face diagonal .45° wedge fixture.: \"xy\", \"yz\" or \"zx\"" "$CALBENCH" simulate bench --plan "$tmp/p.toml" --truth random --out "$tmp/s"
printf '[site]\nlat_deg = 50.0\nlon_deg = 10.0\n[[step]]\nkind = "static"\nmount = "x"\nrpy_deg = [0.0, 0.0, 0.0]\ndwell_s = 5.0\n' > "$tmp/p.toml"
expect_fail "p.toml:7: 'step\[1\].rpy_deg': orientation not reachable" "$CALBENCH" simulate bench --plan "$tmp/p.toml" --truth random --out "$tmp/s"
printf '[site]\nlat_deg = 50.0\nlon_deg = 10.0\n[[step]]\nkind = "static"\ndwel_s = 5.0\n' > "$tmp/p.toml"
expect_fail "'step\[1\].dwel_s': unknown key" "$CALBENCH" simulate bench --plan "$tmp/p.toml" --truth random --out "$tmp/s"
printf '[site\n' > "$tmp/p.toml"
expect_fail "p.toml:1: invalid TOML" "$CALBENCH" simulate bench --plan "$tmp/p.toml" --truth random --out "$tmp/s"
# Truth files
echo '{"format": "calbench-coefficients/1", "device": {"model": "m", "serial": "s"}, "gyro": {"bias": [0,0], "M": []}}' > "$tmp/t.json"
expect_fail "t.json: 'gyro.bias': expected an array of 3" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth "$tmp/t.json" --out "$tmp/s"
# Usage errors
expect_fail "" "$CALBENCH" fit bench "$tmp/does-not-exist"
expect_fail "" "$CALBENCH" fit bench "$tmp/r" --method magic
# --help everywhere
for c in "" "simulate" "simulate bench" "fit" "fit bench"; do "$CALBENCH" $c --help > /dev/null; done
echo "bad input: ok"
