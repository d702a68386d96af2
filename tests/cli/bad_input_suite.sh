#!/usr/bin/env bash
# Bad input across every subcommand (issue 17): each case asserts the exact exit status (2 bad
# input, 1 refused/failed, 0 where a repeat is harmless, as the README promises), that stderr names
# the file (line, field) or the option, that nothing half-written is left behind, and that the
# program did not crash (status >= 128, or a sanitizer report on stderr); numbers in messages carry
# no float noise (99.90000000000055) nor all the digits std::to_string gives 1e308. All cases run;
# the failures are listed at the end. Also run against an ASan/UBSan build (same CALBENCH, SRC, SHARED).
# VERBOSE=1 prints every case's exit status and stderr.
set -uo pipefail
: "${CALBENCH:?}" "${SRC:?}"
T=$(mktemp -d)
RO_MOUNTED=0
cleanup() { [ "$RO_MOUNTED" = 1 ] && umount "$T/ro" 2> /dev/null; rm -rf "$T"; }
trap cleanup EXIT
cd "$T" || exit 1
export CALBENCH_DB="$T/default-does-not-exist.db"  # never the caller's database
unset CALBENCH_OPERATOR CALBENCH_USER  # the stores are by the OS user; approvals name another operator

PASSED=0
FAILED=()
SKIPPED=()
# t ID RC REGEX CMD... : run CMD (stdin empty, 60 s at most); its exit status must be RC and its
# stderr must match the extended regex REGEX (NONE: stderr must be empty). LEFT="p1 p2" before t:
# paths that must not exist afterwards (no output, no half-written file; removed after the check so
# that one failure does not cascade). Any "*.tmp.*" file or ".*.importing-*" folder left fails.
t() {
  local id=$1 want=$2 pat=$3
  shift 3
  local rc why=""
  timeout 60 "$@" > "$T/out.txt" 2> "$T/err.txt" < /dev/null
  rc=$?
  if [ "$rc" = 124 ]; then why="timed out (60 s)"
  elif [ "$rc" -ge 128 ]; then why="crashed (exit $rc)"
  elif grep -Eq "AddressSanitizer|LeakSanitizer|UndefinedBehaviorSanitizer|runtime error:" "$T/err.txt"; then why="sanitizer report"
  elif [ "$rc" != "$want" ]; then why="exit $rc, expected $want"
  elif [ "$pat" = NONE ]; then [ -s "$T/err.txt" ] && why="stderr is not empty"
  elif ! grep -Eq -- "$pat" "$T/err.txt"; then why="stderr does not match /$pat/"
  elif grep -Eq '[0-9]\.0*[1-9][0-9]{10,}|[0-9]{25,}' "$T/err.txt"; then why="a number printed with float noise or all its digits"
  fi
  local p
  for p in ${LEFT:-}; do
    [ -z "$why" ] && [ -e "$p" ] && why="left $p behind"
    rm -rf "$p"
  done
  local tmp
  tmp=$(find "$T" \( -name '*.tmp.*' -o -name '.*.importing-*' \) -print -quit)
  if [ -z "$why" ] && [ -n "$tmp" ]; then why="left a temporary file or folder: $tmp"; fi
  find "$T" \( -name '*.tmp.*' -o -name '.*.importing-*' \) -prune -exec rm -rf {} + 2> /dev/null
  [ -n "${VERBOSE:-}" ] && echo "$id [$rc]: $(tr '\n' ' ' < "$T/err.txt" | cut -c 1-400)"
  if [ -z "$why" ]; then
    PASSED=$((PASSED + 1))
  else
    FAILED+=("$id: $why")
    {
      echo "FAIL $id: $why"
      echo "  command: $*"
      sed 's/^/  stderr: /' "$T/err.txt" | head -8
    } >&2
  fi
}
# ok CMD...: a setup step that must succeed.
ok() { "$@" > "$T/setup.out" 2> "$T/setup.err" || { cat "$T/setup.err" >&2; echo "bad_input_suite: setup failed: $*" >&2; exit 1; }; }

# ---------------------------------------------------------------------------------- valid inputs
ok "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --seed 3 --out bench
ok "$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 2 --until 30 --out rec
ok "$CALBENCH" simulate multipos --seed 1 --out mp
SHA=$(printf 'a%.0s' {1..64})
ok "$CALBENCH" db init --db d.db
ok "$CALBENCH" db store-bench --db d.db --coeffs bench/truth.json --sha256 "$SHA"  # set 1: draft
echo '{"allow_unknown_sigma": true, "require_qc": false, "gyro": {"max_abs_bias_dph": 1e9, "max_abs_scale_ppm": 1e9, "max_abs_skew_ppm": 1e9, "max_sigma_bias_dph": 1e9, "max_sigma_M_ppm": 1e9}, "accel": {"max_abs_bias_mg": 1e9, "max_abs_scale_ppm": 1e9, "max_abs_skew_ppm": 1e9, "max_sigma_bias_mg": 1e9, "max_sigma_M_ppm": 1e9}}' > loose.json
ok "$CALBENCH" db store-bench --db d.db --coeffs bench/truth.json --sha256 "$SHA"  # set 2: approved below
ok "$CALBENCH" db approve 2 --db d.db --thresholds loose.json --operator qc-anna
ok "$CALBENCH" db store-bench --db d.db --coeffs bench/truth.json --sha256 "$SHA"  # set 3: revoked below
ok "$CALBENCH" db revoke 3 --db d.db --reason test
SERIAL=SIM-3
cp d.db d.db.orig

# Hostile files.
: > empty.txt
# Random bytes behind a first byte that no number starts with: the first field is never numeric
# (with /dev/urandom alone, one run in a few hundred began with a digit and a blank).
printf '\xa7' > garbage.bin
head -c 4095 /dev/urandom >> garbage.bin
printf '\x00\x01\x02binary\xff\xfe\n' >> garbage.bin
echo '{"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": "X"}}' > coeffs-like.json
printf '[plan]\nname = "x"\n' > plan.toml
mkdir folder
printf 't_s,a\n0,1\n' > notdb.csv
# A recording whose imu.csv is a copy of rec's, for edits.
mkrec() { rm -rf "$1"; cp -r rec "$1"; }

# ---------------------------------------------------------------------------------- top level
t top-no-command 2 "'calbench' needs a command \(commands: simulate, station" "$CALBENCH"
t top-unknown-command 2 "unknown command 'fti' for 'calbench'; did you mean 'fit'\?" "$CALBENCH" fti bench x
t top-unknown-option 2 "unknown option '--frobnicate' for 'calbench'" "$CALBENCH" --frobnicate
t sub-unknown-option 2 "unknown option '--db' for 'calbench db': a command comes first \(commands: init, devices" "$CALBENCH" db --db d.db devices
t top-unknown-command-far 2 "unknown command 'xyzzy' for 'calbench' \(commands: simulate" "$CALBENCH" xyzzy

# ---------------------------------------------------------------------------------- simulate bench
t sim-sub-missing 2 "'calbench simulate' needs a command \(commands: bench, drive, multipos; calbench simulate --help\)" "$CALBENCH" simulate
t sim-sub-typo 2 "unknown command 'bnech' for 'calbench simulate'; did you mean 'bench'\?" "$CALBENCH" simulate bnech
LEFT="s1" t sim-bench-plan-missing 2 "--plan: .*nope\.toml" "$CALBENCH" simulate bench --plan nope.toml --truth random --out s1
LEFT="s1" t sim-bench-plan-folder 2 "--plan: .*folder" "$CALBENCH" simulate bench --plan folder --truth random --out s1
LEFT="s1" t sim-bench-plan-empty 2 "empty\.txt" "$CALBENCH" simulate bench --plan empty.txt --truth random --out s1
LEFT="s1" t sim-bench-plan-json 2 "coeffs-like\.json:1: invalid TOML" "$CALBENCH" simulate bench --plan coeffs-like.json --truth random --out s1
LEFT="s1" t sim-bench-plan-binary 2 "garbage\.bin:[0-9]+" "$CALBENCH" simulate bench --plan garbage.bin --truth random --out s1
sed 's/^lat_deg = 52.0/lat_deg = 95.0/' "$SRC/tests/data/short_plan.toml" > lat.toml
LEFT="s1" t sim-bench-plan-range 2 "lat\.toml:[0-9]+: 'site\.lat_deg': out of range \[-90, 90\]" "$CALBENCH" simulate bench --plan lat.toml --truth random --out s1
LEFT="s1" t sim-bench-truth-missing 2 "nope\.json" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth nope.json --out s1
LEFT="s1" t sim-bench-truth-binary 2 "garbage\.bin" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth garbage.bin --out s1
LEFT="s1" t sim-bench-truth-toml 2 "plan\.toml:1" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth plan.toml --out s1
LEFT="s1" t sim-bench-seed-negative 2 "--seed: .*'-1'" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --seed -1 --out s1
LEFT="s1" t sim-bench-seed-nan 2 "--seed" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --seed nan --out s1
LEFT="s1" t sim-bench-seed-huge 2 "--seed: .*99999999999999999999" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --seed 99999999999999999999 --out s1
LEFT="s1" t sim-bench-inject-unknown 2 "--inject.*warp_drive" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --inject warp_drive:value=1 --out s1
LEFT="s1" t sim-bench-inject-nan 2 "--inject.*time_offset.*nan|nan.*time_offset" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --inject time_offset:value=nan --out s1
LEFT="s1" t sim-bench-unknown-option 2 "'--sede' is not an option of 'calbench simulate bench'; did you mean '--seed'\?" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --sede 3 --out s1
t sim-bench-out-exists 2 "bench: already holds a recording.*--force" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --out bench
t sim-bench-out-is-file 2 "empty\.txt: is a file, not a folder" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --out empty.txt

# ---------------------------------------------------------------------------------- simulate drive
LEFT="s2" t sim-drive-route-missing 2 "--route: .*nope\.toml" "$CALBENCH" simulate drive --route nope.toml --truth random --out s2
LEFT="s2" t sim-drive-route-binary 2 "garbage\.bin" "$CALBENCH" simulate drive --route garbage.bin --truth random --out s2
LEFT="s2" t sim-drive-until-nan 2 "--until: .*'nan'" "$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --until nan --out s2
LEFT="s2" t sim-drive-until-negative 2 "--until: .*'-5'" "$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --until -5 --out s2
LEFT="s2" t sim-drive-until-1e999 2 "--until: .*'1e999'" "$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --until 1e999 --out s2
echo '{"gyro": {"drift_sigma_deg_h": "lots"}}' > noise.json
LEFT="s2" t sim-drive-noise-field 2 "noise\.json: 'gyro\.drift_sigma_deg_h'" "$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --noise noise.json --until 1 --out s2
echo '{"gyro": {"drift_sigma_deg_h": -3}}' > noise-neg.json
LEFT="s2" t sim-drive-noise-negative 2 "noise-neg\.json: 'gyro\.drift_sigma_deg_h'" "$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --noise noise-neg.json --until 1 --out s2

# ---------------------------------------------------------------------------------- simulate multipos
LEFT="s3" t sim-mp-poses-negative 2 "--poses: .*'-3'" "$CALBENCH" simulate multipos --poses -3 --out s3
LEFT="s3" t sim-mp-still-reversed 2 "--still: MIN 3 s is above MAX 1 s" "$CALBENCH" simulate multipos --still 3,1 --out s3
LEFT="s3" t sim-mp-still-one 2 "--still: expected MIN,MAX in seconds \(e\.g\. 1,3\), got '3'" "$CALBENCH" simulate multipos --still 3 --out s3
LEFT="s3" t sim-mp-still-nan 2 "--still: expected MIN,MAX" "$CALBENCH" simulate multipos --still 1,nan --out s3
LEFT="s3" t sim-mp-still-plus-minus 2 "--still: expected MIN,MAX" "$CALBENCH" simulate multipos --still +-1,3 --out s3
LEFT="s3" t sim-mp-class-unknown 2 "--device-class: 'nope' is neither a class file nor a known class" "$CALBENCH" simulate multipos --device-class nope --out s3
LEFT="s3" t sim-mp-class-file-missing 2 "nope\.toml: '--device-class': no such class file" "$CALBENCH" simulate multipos --device-class nope.toml --out s3
LEFT="s3" t sim-mp-class-file-binary 2 "garbage\.bin" "$CALBENCH" simulate multipos --device-class garbage.bin --out s3
LEFT="s3" t sim-mp-noise-negative 2 "--noise-factor: .*'-1'" "$CALBENCH" simulate multipos --noise-factor -1 --out s3
LEFT="s3" t sim-mp-rate-1e999 2 "--rate: .*'1e999'" "$CALBENCH" simulate multipos --rate 1e999 --out s3
LEFT="s3" t sim-mp-site-lat-range 2 "--site-lat: .*'91'" "$CALBENCH" simulate multipos --site-lat 91 --out s3
LEFT="s3" t sim-mp-opening-nan 2 "--opening-still: .*'nan'" "$CALBENCH" simulate multipos --opening-still nan --out s3
LEFT="s3" t sim-mp-model-empty 2 "--model" "$CALBENCH" simulate multipos --model "" --out s3
LEFT="s3" t sim-mp-unknown-option 2 "'--sede' is not an option of 'calbench simulate multipos'; did you mean '--seed'\?" "$CALBENCH" simulate multipos --sede 3 --out s3
t sim-mp-out-exists 2 "mp: already holds a recording.*--force" "$CALBENCH" simulate multipos --out mp
t sim-mp-out-is-file 2 "empty\.txt: is a file, not a folder" "$CALBENCH" simulate multipos --out empty.txt

# ---------------------------------------------------------------------------------- station run
t station-sub-typo 2 "unknown command 'rnu' for 'calbench station'; did you mean 'run'\?" "$CALBENCH" station rnu
LEFT="st" t station-plan-missing 2 "--plan: .*nope\.toml" "$CALBENCH" station run --emulated --plan nope.toml --out st
LEFT="st" t station-plan-json 2 "not started \(nothing ran\): coeffs-like\.json:1" "$CALBENCH" station run --emulated --plan coeffs-like.json --out st
LEFT="st" t station-max-repeats-negative 2 "--max-repeats: .*'-1'" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --max-repeats -1 --out st
LEFT="st" t station-seed-float 2 "--seed: .*'1\.5'" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --seed 1.5 --out st
LEFT="st" t station-inject-unknown 2 "--inject: 'warp'" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --inject warp=1 --out st
LEFT="st" t station-inject-nan 2 "--inject: 'table-kill-at': expected a finite time >= 0 s, got 'nan'" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --inject table-kill-at=nan --out st
LEFT="st" t station-inject-skip-zero 2 "--inject: 'imu-skip-every': expected a whole number >= 1, got '0'" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --inject imu-skip-every=0 --out st
LEFT="st" t station-inject-not-emulated 2 "--inject.*needs --emulated" "$CALBENCH" station run --plan "$SRC/tests/data/short_plan.toml" --inject imu-flags=0x0008 --out st
LEFT="st" t station-no-table 2 "not started \(nothing ran\): --table is required without --emulated" "$CALBENCH" station run --plan "$SRC/tests/data/short_plan.toml" --out st
LEFT="st" t station-imu-with-emulated 2 "--imu: not used with --emulated" "$CALBENCH" station run --emulated --imu ft232h --plan "$SRC/tests/data/short_plan.toml" --out st
LEFT="st" t station-table-uri 2 "not started \(nothing ran\): --table: table URI 'bogus://x'" "$CALBENCH" station run --plan "$SRC/tests/data/short_plan.toml" --table bogus://x --imu ft232h --out st
LEFT="st" t station-imu-uri 2 "--imu.*nonsense" "$CALBENCH" station run --plan "$SRC/tests/data/short_plan.toml" --table modbus-tcp://127.0.0.1:1 --imu nonsense --out st
LEFT="st" t station-db-not-db 2 "not started \(nothing ran\): notdb\.csv: not a calbench database" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --db notdb.csv --out st
LEFT="st" t station-db-missing-folder 2 "not started \(nothing ran\): nowhere/s\.db: cannot write: the folder nowhere does not exist" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --db nowhere/s.db --out st
t station-out-is-file 2 "not started \(nothing ran\): empty\.txt: is a file, not a folder" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --out empty.txt
printf '[[slot]]\nname = "a"\nimu = "mcp2210:S1"\n[[slot]]\nname = "a"\nimu = "mcp2210:S2"\n' > fx-dup.toml
printf '[[slot]]\nname = "a"\nimu = "spi0"\n' > fx-uri.toml
printf '[[slot]]\nname = "a"\nimu = "ft232h:F1"\n[[slot]]\nname = "b"\nimu = "ft232h://F1"\n' > fx-cs.toml
LEFT="st" t station-fixture-duplicate-slot 2 "not started \(nothing ran\): fx-dup\.toml:5: 'slot\[2\]\.name': duplicate slot 'a'" "$CALBENCH" station run --emulated --fixture fx-dup.toml --plan "$SRC/tests/data/short_plan.toml" --out st
LEFT="st" t station-fixture-bad-uri 2 "fx-uri\.toml:3: 'slot\[1\]\.imu': 'spi0': expected ft232h" "$CALBENCH" station run --fixture fx-uri.toml --table modbus-tcp://127.0.0.1:1 --plan "$SRC/tests/data/short_plan.toml" --out st
LEFT="st" t station-fixture-one-chip-select 2 "fx-cs\.toml:6: 'slot\[2\]\.imu': .*two units on one chip select" "$CALBENCH" station run --fixture fx-cs.toml --table modbus-tcp://127.0.0.1:1 --plan "$SRC/tests/data/short_plan.toml" --out st
LEFT="st" t station-units-zero 2 "--units: .*'0'" "$CALBENCH" station run --emulated --units 0 --plan "$SRC/tests/data/short_plan.toml" --out st
LEFT="st" t station-inject-slot-table 2 "--inject: 'table-kill-at': a fault of the table" "$CALBENCH" station run --emulated --units 2 --inject 1:table-kill-at=3 --plan "$SRC/tests/data/short_plan.toml" --out st
LEFT="st" t station-inject-flags-from-alone 2 "--inject: '2:imu-flags-from': needs 2:imu-flags=BITS" "$CALBENCH" station run --emulated --units 2 --inject 2:imu-flags-from=3 --plan "$SRC/tests/data/short_plan.toml" --out st

# ---------------------------------------------------------------------------------- emulate table
t emulate-sub-typo 2 "unknown command 'tabel' for 'calbench emulate'; did you mean 'table'\?" "$CALBENCH" emulate tabel
t emulate-listen-no-port 2 "--listen.*HOST:PORT" "$CALBENCH" emulate table --listen localhost
t emulate-listen-hostname 2 "--listen: 'listen': HOST must be an IPv4 address such as 127\.0\.0\.1, got 'no\.such\.host\.invalid'" "$CALBENCH" emulate table --listen no.such.host.invalid:0
t emulate-listen-port-range 2 "--listen.*0\.\.65535" "$CALBENCH" emulate table --listen 127.0.0.1:70000
t emulate-watchdog-inf 2 "--watchdog: .*'inf'" "$CALBENCH" emulate table --listen 127.0.0.1:0 --watchdog inf
t emulate-speed-zero 2 "--speed: .*'0'" "$CALBENCH" emulate table --listen 127.0.0.1:0 --speed 0
t emulate-order 2 "--order" "$CALBENCH" emulate table --listen 127.0.0.1:0 --order dcba

# ---------------------------------------------------------------------------------- fit bench
LEFT="c.json" t fit-bench-dir-missing 2 "dir: .*nope" "$CALBENCH" fit bench nope --out c.json
LEFT="c.json" t fit-bench-dir-is-file 2 "dir: .*empty\.txt" "$CALBENCH" fit bench empty.txt --out c.json
LEFT="c.json" t fit-bench-empty-folder 2 "folder/meta\.json" "$CALBENCH" fit bench folder --out c.json
LEFT="c.json" t fit-bench-block-nan 2 "--block: .*'nan'" "$CALBENCH" fit bench bench --block nan --out c.json
LEFT="c.json" t fit-bench-block-range 2 "--block: .*'0'" "$CALBENCH" fit bench bench --block 0 --out c.json
mkdir -p b1 && cp bench/meta.json bench/reference.csv b1/
head -c 2000 bench/imu.csv | head -n 5 > b1/imu.csv; echo "0.05,0,0" >> b1/imu.csv; tail -n +6 bench/imu.csv | head -50 >> b1/imu.csv
LEFT="c.json" t fit-bench-short-row 2 "b1/imu\.csv:6: '[a-z_]+': missing field" "$CALBENCH" fit bench b1 --out c.json
mkdir -p b2 && cp bench/meta.json bench/reference.csv b2/
{ head -n 3 bench/imu.csv; echo "0.0149,1e999,0,0,0,0,-9.8"; } > b2/imu.csv
LEFT="c.json" t fit-bench-1e999 2 "b2/imu\.csv:4: 'gx_rad_s'" "$CALBENCH" fit bench b2 --out c.json
mkdir -p b5 && cp bench/meta.json bench/reference.csv b5/
{ head -n 4 bench/imu.csv; sed -n 4p bench/imu.csv; } > b5/imu.csv
LEFT="c.json" t fit-bench-duplicated-time 2 "b5/imu\.csv:5: 't_s': duplicated time [0-9.e-]+$" "$CALBENCH" fit bench b5 --out c.json
mkdir -p b6 && cp bench/meta.json bench/reference.csv b6/
{ head -n 3 bench/imu.csv; printf '0.001,\x01\xff\xfe\x1b[31m,0,0,0,0,-9.8,25\n'; } > b6/imu.csv
LEFT="c.json" t fit-bench-binary-field 2 "b6/imu\.csv:4: 'gx_rad_s': not a number: '\\\\x01\\\\xFF\\\\xFE\\\\x1B\[31m'$" "$CALBENCH" fit bench b6 --out c.json
mkdir -p b3 && cp bench/meta.json bench/imu.csv b3/
sed 's/^t_s,\(.*\),step,/t_s,\1,stage,/' bench/reference.csv > b3/reference.csv
LEFT="c.json" t fit-bench-ref-header 2 "b3/reference\.csv:2: 'step': missing required column" "$CALBENCH" fit bench b3 --out c.json
mkdir -p b4 && cp bench/imu.csv bench/reference.csv b4/ && cp garbage.bin b4/meta.json
LEFT="c.json" t fit-bench-meta-binary 2 "b4/meta\.json" "$CALBENCH" fit bench b4 --out c.json
mkdir -p b7 && cp bench/imu.csv bench/reference.csv b7/ && sed 's/"imu_rate_hz": *[0-9.e+]*/"imu_rate_hz": 1e300/' bench/meta.json > b7/meta.json
LEFT="c.json" t fit-bench-meta-rate 2 "b7/meta\.json: 'imu_rate_hz': 1e\+300 Hz is not an IMU rate" "$CALBENCH" fit bench b7 --out c.json
mkdir -p b8 && cp bench/imu.csv bench/reference.csv b8/ && python3 -c "import sys; t = open('bench/meta.json').read(); b = t.rindex('}'); open('b8/meta.json', 'w').write(t[:b].rstrip() + ',\n  \"imu_rate_hz\": 1\n}\n')"
LEFT="c.json" t fit-bench-meta-duplicate-key 2 "b8/meta\.json: 'imu_rate_hz': duplicate key 'imu_rate_hz'" "$CALBENCH" fit bench b8 --out c.json
t fit-bench-out-missing-folder 2 "nowhere/c\.json: cannot write: the folder nowhere does not exist" "$CALBENCH" fit bench bench --out nowhere/c.json
t fit-bench-out-is-folder 2 "folder: is a folder" "$CALBENCH" fit bench bench --out folder
LEFT="c.json" t fit-bench-effects-binary 2 "garbage\.bin" "$CALBENCH" fit bench bench --effects garbage.bin --out c.json

# ---------------------------------------------------------------------------------- fit drive
t fit-sub-typo 2 "unknown command 'dirve' for 'calbench fit'; did you mean 'drive'\?" "$CALBENCH" fit dirve rec
LEFT="r.json" t fit-drive-allowance-nan 2 "--allowance-gyro-scale-ppm: expected a finite number >= 0, got 'nan'" "$CALBENCH" fit drive rec --out r.json --allowance-gyro-scale-ppm nan
LEFT="r.json" t fit-drive-unknown-option 2 "'--allowance-gyro-scale' is not an option of 'calbench fit drive'; did you mean '--allowance-gyro-scale-ppm'\?" "$CALBENCH" fit drive rec --out r.json --allowance-gyro-scale 3
LEFT="r.json" t fit-drive-sigma-pos-negative 2 "--sigma-pos: expected a finite number > 0, got '-1'" "$CALBENCH" fit drive rec --out r.json --sigma-pos -1
LEFT="r.json" t fit-drive-window-reversed 2 "--window: T1 must be after T0" "$CALBENCH" fit drive rec --out r.json --window 20:10
LEFT="r.json" t fit-drive-window-garbage 2 "--window: .*'5abc:10'" "$CALBENCH" fit drive rec --out r.json --window 5abc:10
LEFT="r.json" t fit-drive-window-nan 2 "--window: .*'nan:10'" "$CALBENCH" fit drive rec --out r.json --window nan:10
LEFT="r.json" t fit-drive-obs 2 "--obs.*'?speed" "$CALBENCH" fit drive rec --out r.json --obs pos,speed
LEFT="r.json" t fit-drive-aiding 2 "--aiding.*radar" "$CALBENCH" fit drive rec --out r.json --aiding radar
LEFT="r.json" t fit-drive-coeffs-json-wrong 2 "coeffs-like\.json: 'gyro'" "$CALBENCH" fit drive rec --out r.json --coeffs coeffs-like.json
LEFT="r.json" t fit-drive-drift-models-empty 2 "empty\.txt" "$CALBENCH" fit drive rec --out r.json --drift-models empty.txt
mkdir -p r1 && cp rec/meta.json rec/imu.csv r1/
LEFT="r.json" t fit-drive-no-reference 2 "r1.*(reference\.csv|gnss\.csv)" "$CALBENCH" fit drive r1 --out r.json
mkrec r2; sed -i '3s/^\([^,]*\),[^,]*,/\1,abc,/' r2/imu.csv
LEFT="r.json" t fit-drive-non-numeric 2 "r2/imu\.csv:3: '[a-z_]+': not a number" "$CALBENCH" fit drive r2 --out r.json
LEFT="r.json" t fit-drive-missing-out 2 "--out.*required" "$CALBENCH" fit drive rec
LEFT="r.json" t fit-drive-series-folder 2 "folder" "$CALBENCH" fit drive rec --out r.json --series folder --window 0:5 --qc-horizon 1

# ---------------------------------------------------------------------------------- identify
LEFT="m.json" t identify-missing 2 "input: .*nope\.csv" "$CALBENCH" identify nope.csv --out m.json
LEFT="m.json" t identify-empty 2 "empty\.txt" "$CALBENCH" identify empty.txt --out m.json
LEFT="m.json" t identify-binary 2 "garbage\.bin" "$CALBENCH" identify garbage.bin --out m.json
{ echo "t_s,x"; for i in $(seq 0 99); do echo "$i,$((i % 7))"; done; } > series.csv
LEFT="m.json" t identify-max-lag-nan 2 "--max-lag: .*'nan'" "$CALBENCH" identify series.csv --max-lag nan --out m.json
LEFT="m.json" t identify-decimate-zero 2 "--decimate: .*'0'" "$CALBENCH" identify series.csv --decimate 0 --out m.json
LEFT="m.json" t identify-from-nan 2 "--from: .*'nan'" "$CALBENCH" identify series.csv --from nan --out m.json
LEFT="m.json" t identify-column-recording 2 "--column: 'speed': unknown column for a recording" "$CALBENCH" identify rec --column speed --out m.json
LEFT="m.json" t identify-from-recording 2 "--from: rec is a recording folder: --from applies to CSV input" "$CALBENCH" identify rec --from 5 --out m.json
LEFT="m.json" t identify-folder-no-meta 2 "folder/meta\.json" "$CALBENCH" identify folder --out m.json

# ---------------------------------------------------------------------------------- qc
t qc-horizon-nan 2 "--horizon: .*'nan'" "$CALBENCH" qc rec --coeffs none --horizon nan
t qc-horizon-negative 2 "--horizon: .*'-10'" "$CALBENCH" qc rec --coeffs none --horizon -10
t qc-from-inf 2 "--from: .*'inf'" "$CALBENCH" qc rec --coeffs none --from inf
t qc-coeffs-missing-file 2 "nope\.json" "$CALBENCH" qc rec --coeffs nope.json
t qc-coeffs-binary 2 "garbage\.bin" "$CALBENCH" qc rec --coeffs garbage.bin
t qc-coeffs-required 2 "--coeffs.*required" "$CALBENCH" qc rec
t qc-dir-bench 2 "bench.*(drive|reference)" "$CALBENCH" qc bench --coeffs none
LEFT="q.png" t qc-from-after-end 2 "--from|rec" "$CALBENCH" qc rec --coeffs none --from 1e6 --plot q.png

# ---------------------------------------------------------------------------------- diagnose
t diagnose-dir-missing 2 "dir: .*nope" "$CALBENCH" diagnose nope
t diagnose-empty-folder 2 "folder/meta\.json" "$CALBENCH" diagnose folder
LEFT="imp.json" t diagnose-coeffs-binary 2 "garbage\.bin" "$CALBENCH" diagnose rec --coeffs garbage.bin --out imp.json
LEFT="imp.json" t diagnose-coeffs-folder 2 "--coeffs: .*folder" "$CALBENCH" diagnose rec --coeffs folder --out imp.json
LEFT="imp.json" t diagnose-plan-on-drive 2 "--plan: rec is a drive recording: --plan .* applies to bench recordings" "$CALBENCH" diagnose rec --plan "$SRC/tests/data/short_plan.toml" --out imp.json
LEFT="imp.json" t diagnose-no-innovations-on-bench 2 "--no-innovations: bench is a bench recording" "$CALBENCH" diagnose bench --no-innovations --out imp.json
mkrec r3; : > r3/reference.csv
t diagnose-empty-reference 2 "r3/reference\.csv: empty file" "$CALBENCH" diagnose r3

# ---------------------------------------------------------------------------------- db
t db-sub-typo 2 "unknown command 'aprove' for 'calbench db'; did you mean 'approve'\?" "$CALBENCH" db aprove 1
t db-init-missing-folder 2 "nowhere/x\.db: cannot create the database: the folder nowhere does not exist" "$CALBENCH" db init --db nowhere/x.db
t db-init-folder 2 "folder: is a folder, not a database file" "$CALBENCH" db init --db folder
t db-init-binary 2 "garbage\.bin: not a calbench database" "$CALBENCH" db init --db garbage.bin
t db-devices-missing 2 "nope\.db: no database here" "$CALBENCH" db devices --db nope.db
# PostgreSQL URIs (no server needed): malformed → 2, unreachable → 1; a password is never echoed,
# and a station or store-bench with a malformed URI writes no journal.
t db-pg-bad-port 2 "postgresql://st@127\.0\.0\.1:x1/c: not a valid PostgreSQL URI: port 'x1' is not a port number" "$CALBENCH" db devices --db "postgresql://st@127.0.0.1:x1/c"
t db-pg-port-range 2 "port '70000' is not a port number" "$CALBENCH" db devices --db "postgresql://st@127.0.0.1:70000/c"
t db-pg-no-database 2 "postgresql://st@127\.0\.0\.1:5432: not a valid PostgreSQL URI: no database named" "$CALBENCH" db devices --db "postgresql://st@127.0.0.1:5432"
t db-pg-sslmode 2 "sslmode 'sometimes' is not one of" "$CALBENCH" db devices --db "postgresql://st@h/c?sslmode=sometimes"
t db-pg-bad-param 2 "not a valid PostgreSQL URI \(invalid URI query parameter" "$CALBENCH" db devices --db "postgresql://st@h/c?colour=blue"
t db-pg-bad-escape 2 "^calbench: error: postgresql://st@h/c: not a valid PostgreSQL URI \(invalid password part|invalid percent" "$CALBENCH" db devices --db "postgresql://st:pa%zzss@h/c"
grep -q "pa%zzss\|zzss" "$T/err.txt" && FAILED+=("db-pg-bad-escape: the password was echoed")
t db-pg-scheme-typo 2 "postgressql://st@h/c: not a database: neither a SQLite file nor a postgresql:// \\(or postgres://\\) URI" "$CALBENCH" db devices --db "postgressql://st@h/c"
t db-pg-unreachable 1 "postgresql://st@127\.0\.0\.1:1/c: cannot reach the database server" "$CALBENCH" db devices --db "postgresql://st:Hunter2pw@127.0.0.1:1/c"
grep -q "Hunter2pw" "$T/err.txt" "$T/out.txt" && FAILED+=("db-pg-unreachable: the password was echoed")
LEFT="j.db" t db-pg-store-bench-malformed 2 "not a valid PostgreSQL URI" "$CALBENCH" db store-bench --db "postgresql://st@h:0/c" --coeffs bench/truth.json --sha256 "$SHA" --journal j.db
LEFT="j.db st" t station-pg-malformed 2 "not started \(nothing ran\): .*not a valid PostgreSQL URI" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --db "postgresql://st@h/c?sslmode=x" --journal j.db --out st
t db-sync-sqlite 2 "--db: db sync forwards a station's journal to a central PostgreSQL store" "$CALBENCH" db sync --db d.db
t db-sync-no-journal 2 "nojournal\.db: no journal here \(a station run or db store-bench with a PostgreSQL --db writes it\)" "$CALBENCH" db sync --db "postgresql://st@127.0.0.1:1/c" --journal nojournal.db
t db-init-roles-sqlite 2 "--roles: roles are PostgreSQL's" "$CALBENCH" db init --db d.db --roles
t db-devices-not-db 2 "notdb\.csv: not a calbench database" "$CALBENCH" db devices --db notdb.csv
: > empty.db
t db-devices-empty-file 2 "empty\.db: not a calbench database \(an empty file" "$CALBENCH" db devices --db empty.db
[ -s empty.db ] && FAILED+=("db-devices-empty-file: a schema was written into the empty file")
python3 -c "import sqlite3; c = sqlite3.connect('other.sqlite'); c.execute('CREATE TABLE parts(a)'); c.commit()"
cp other.sqlite other.orig
t db-devices-other-sqlite 2 "other\.sqlite: not a calbench database \(another program's SQLite database\)" "$CALBENCH" db devices --db other.sqlite
cmp -s other.sqlite other.orig || FAILED+=("db-devices-other-sqlite: another program's database was changed")
t report-db-empty-file 2 "empty\.db: not a calbench database" "$CALBENCH" report fleet --html rep.html --db empty.db
t report-db-binary 2 "garbage\.bin: not a calbench database" "$CALBENCH" report fleet --html rep.html --db garbage.bin
t db-show-unknown-serial 2 "SERIAL: unknown device 'NOPE-1'" "$CALBENCH" db show NOPE-1 --db d.db
t db-history-unknown-serial 2 "SERIAL: unknown device 'NOPE-1'" "$CALBENCH" db history NOPE-1 --db d.db
t db-show-serial-required 2 "SERIAL is required" "$CALBENCH" db show --db d.db
t db-history-db-missing 2 "nope\.db: no database here" "$CALBENCH" db history "$SERIAL" --db nope.db
t db-fleet-not-db 2 "notdb\.csv: not a calbench database" "$CALBENCH" db fleet --db notdb.csv
t db-devices-unknown-option 2 "'--jsn' is not an option of 'calbench db devices'; did you mean '--json'\?" "$CALBENCH" db devices --db d.db --jsn
t db-approve-not-a-number 2 "SET: .*'abc'" "$CALBENCH" db approve abc --db d.db
t db-approve-zero 2 "SET: expected a whole number >= 1, got '0'" "$CALBENCH" db approve 0 --db d.db
t db-approve-unknown-set 2 "no coefficient set 99" "$CALBENCH" db approve 99 --db d.db
t db-approve-thresholds-binary 2 "garbage\.bin" "$CALBENCH" db approve 1 --db d.db --thresholds garbage.bin
echo '{"gyro": {"max_abs_bias_dph": "high"}}' > th-bad.json
t db-approve-thresholds-field 2 "th-bad\.json: 'gyro\.max_abs_bias_dph'" "$CALBENCH" db approve 1 --db d.db --thresholds th-bad.json
# Issue 35 tryout: a key twice in one object (the last would win, loosening a limit), a number beyond
# a double, a folder given as the file.
printf '{"bench": {"max_chi2_dof": {"gyro": 3,\n "gyro": 1000}}}\n' > th-dup.json
t db-approve-thresholds-duplicate-key 2 "th-dup\.json: 'bench\.max_chi2_dof\.gyro': duplicate key 'gyro'" "$CALBENCH" db approve 1 --db d.db --thresholds th-dup.json --operator qc-anna
printf '{"gyro": {\n "max_abs_bias_dph": 1e999}}\n' > th-big.json
t db-approve-thresholds-overflow 2 "th-big\.json:2: 'gyro\.max_abs_bias_dph': number out of range" "$CALBENCH" db approve 1 --db d.db --thresholds th-big.json --operator qc-anna
t db-approve-thresholds-folder 2 "folder: is a folder, not a JSON file" "$CALBENCH" db approve 1 --db d.db --thresholds folder --operator qc-anna
t db-revoke-unknown 2 "no coefficient set 42" "$CALBENCH" db revoke 42 --db d.db
t db-revoke-reason-control 2 "reason.*control" "$CALBENCH" db revoke 1 --db d.db --reason $'bad\x01reason'
LEFT="e.json" t db-export-unknown 2 "no coefficient set 77" "$CALBENCH" db export 77 --db d.db --out e.json
t db-export-out-missing-folder 2 "nowhere/e\.json: cannot write: the folder nowhere does not exist" "$CALBENCH" db export 2 --db d.db --out nowhere/e.json
t db-export-out-folder 2 "folder: is a folder" "$CALBENCH" db export 2 --db d.db --out folder
t db-fleet-folder 2 "folder: is a folder, not a database file" "$CALBENCH" db fleet --db folder
t db-import-missing 2 "nope\.json" "$CALBENCH" db import-inmotion nope.json --db d.db
t db-import-empty 2 "empty\.txt" "$CALBENCH" db import-inmotion empty.txt --db d.db
t db-import-coeffs 2 "coeffs-like\.json" "$CALBENCH" db import-inmotion coeffs-like.json --db d.db
t db-import-parent-negative 2 "--parent: .*'-2'" "$CALBENCH" db import-inmotion coeffs-like.json --db d.db --parent -2
t db-store-coeffs-binary 2 "garbage\.bin" "$CALBENCH" db store-bench --db d.db --coeffs garbage.bin --sha256 "$SHA"
t db-store-sha-bad 2 "sha256.*xyz|xyz.*sha256" "$CALBENCH" db store-bench --db d.db --coeffs bench/truth.json --sha256 xyz
t db-store-qc-nan 2 "--qc rms: 'nan' is not a finite number" "$CALBENCH" db store-bench --db d.db --coeffs bench/truth.json --sha256 "$SHA" --qc rms=nan
t db-store-qc-sample 2 "--qc rms: sample 'sideways'" "$CALBENCH" db store-bench --db d.db --coeffs bench/truth.json --sha256 "$SHA" --qc rms=1:2:m:sideways
t db-store-outcome 2 "--outcome.*maybe" "$CALBENCH" db store-bench --db d.db --coeffs bench/truth.json --sha256 "$SHA" --outcome maybe
t db-store-recording-no-imu 2 "folder/imu\.csv: recording has no imu\.csv" "$CALBENCH" db store-bench --db d.db --coeffs bench/truth.json --recording folder
cmp -s d.db d.db.orig || FAILED+=("db: a refused command changed the database")  # nothing stored by any of the above
# Refusals (exit 1, recorded in the audit log) and repeats that change nothing (exit 0).
t db-approve-refused 1 "set 1 NOT approved" "$CALBENCH" db approve 1 --db d.db
t db-approve-again 0 NONE "$CALBENCH" db approve 2 --db d.db --thresholds loose.json --operator qc-anna
grep -q "set 2 is already approved (no change)" out.txt || FAILED+=("db-approve-again: stdout lacks 'already approved'")
t db-approve-revoked 1 "set 3 NOT approved|revoked" "$CALBENCH" db approve 3 --db d.db --thresholds loose.json --operator qc-anna
t db-approve-unsigned 1 "approval needs a named operator: --operator NAME or CALBENCH_OPERATOR" "$CALBENCH" db approve 1 --db d.db --thresholds loose.json
t db-approve-operator-at 2 "--operator: operator name 'qa@lab' must not contain '@'" "$CALBENCH" db approve 1 --db d.db --operator qa@lab
t db-approve-operator-empty 2 "--operator: operator name '' must be 1 to 64 characters" "$CALBENCH" db approve 1 --db d.db --operator ""
t db-approve-operator-env 2 "CALBENCH_OPERATOR: operator name ' x' must not be blank or start or end with a space" env "CALBENCH_OPERATOR= x" "$CALBENCH" db approve 1 --db d.db
t db-settings-unknown 2 "unknown setting 'five_eyes' \\(settings: four_eyes\\)" "$CALBENCH" db settings five_eyes on --db d.db --operator qc-anna
t db-settings-value 2 "four_eyes: 'maybe' is not one of: on, off" "$CALBENCH" db settings four_eyes maybe --db d.db --operator qc-anna
t db-settings-unsigned 1 "changing a setting needs a named operator" "$CALBENCH" db settings four_eyes off --db d.db
t provision-operator-control 2 "--operator: operator name .* contains control characters" "$CALBENCH" provision 1001 --export p.json --db d.db --operator "$(printf 'a\tb')"
t db-revoke-again 0 NONE "$CALBENCH" db revoke 3 --db d.db
grep -q "set 3 is already revoked (no change)" out.txt || FAILED+=("db-revoke-again: stdout lacks 'already revoked'")

# ---------------------------------------------------------------------------------- provision
t prov-unknown-serial 2 "SERIAL: unknown device 'NOPE-1'" "$CALBENCH" provision NOPE-1 --db d.db --export p.json
t prov-both-targets 2 "--to-device.*--export|--export.*--to-device" "$CALBENCH" provision "$SERIAL" --db d.db --to-device emu://1 --export p.json
t prov-no-target 2 "give --to-device IMU-URI or --export FILE" "$CALBENCH" provision "$SERIAL" --db d.db
t prov-draft-set 1 "set 1 is draft: only approved sets are provisioned" "$CALBENCH" provision "$SERIAL" --db d.db --set 1 --export p.json
t prov-set-zero 2 "--set: .*'0'" "$CALBENCH" provision "$SERIAL" --db d.db --set 0 --export p.json
t prov-uri-no-scheme 2 "--to-device: '/dev/spidev0': expected ft232h\[:USB-SERIAL\]\[#csN\] or mcp2210\[:USB-SERIAL\]\[#csN\] .*or emu://SERIAL" "$CALBENCH" provision "$SERIAL" --db d.db --to-device /dev/spidev0
t prov-uri-scheme 2 "--to-device: 'usb://1': unknown IMU URI scheme 'usb'" "$CALBENCH" provision "$SERIAL" --db d.db --to-device usb://1
t prov-uri-serial 2 "--to-device: 'emu://70000': emulated SERIAL_NUM is 16-bit" "$CALBENCH" provision "$SERIAL" --db d.db --to-device emu://70000
t prov-uri-option 2 "--to-device: 'emu://3\?speed=2': unknown emulator option 'speed'" "$CALBENCH" provision "$SERIAL" --db d.db --to-device 'emu://3?speed=2'
t prov-uri-ft232h-cs 2 "--to-device: 'ft232h:F1#cs1': the FT232H bus drives chip select cs0 \(ADBUS3\) only" "$CALBENCH" provision "$SERIAL" --db d.db --to-device 'ft232h:F1#cs1'
t prov-uri-bridge-option 2 "--to-device: 'mcp2210:A\?x=1': options after '\?' are for an emulated unit" "$CALBENCH" provision "$SERIAL" --db d.db --to-device 'mcp2210:A?x=1'
t prov-export-missing-folder 2 "nowhere/p\.json: cannot write: the folder nowhere does not exist" "$CALBENCH" provision "$SERIAL" --db d.db --export nowhere/p.json
t prov-db-missing 2 "nope\.db: no database here" "$CALBENCH" provision "$SERIAL" --db nope.db --export p.json

# ---------------------------------------------------------------------------------- report
LEFT="rep.html" t report-db-missing 2 "nope\.db: no database here" "$CALBENCH" report "$SERIAL" --html rep.html --db nope.db
LEFT="rep.html" t report-unknown-serial 2 "NOPE-1" "$CALBENCH" report NOPE-1 --html rep.html --db d.db
LEFT="rep.html" t report-thresholds-binary 2 "garbage\.bin" "$CALBENCH" report "$SERIAL" --html rep.html --db d.db --thresholds garbage.bin
t report-html-missing-folder 2 "nowhere/rep\.html: cannot write: the folder nowhere does not exist" "$CALBENCH" report "$SERIAL" --html nowhere/rep.html --db d.db
t report-html-required 2 "--html.*required" "$CALBENCH" report "$SERIAL" --db d.db

# ---------------------------------------------------------------------------------- import kf-gins
printf '1.00 0 0 0 0 0 0\n1.01 0 0 0 0 0 0\n1.02 0 0 0 0 0 0\n' > imu.txt
printf '0 1.00 30 114 20 0 0 0 0 0 0\n0 1.02 30 114 20 0 0 0 0 0 0\n' > truth.nav
t import-sub-typo 2 "unknown command 'kfgins' for 'calbench import'; did you mean 'kf-gins'\?" "$CALBENCH" import kfgins
LEFT="kf" t import-imu-missing 2 "--imu: .*nope\.txt" "$CALBENCH" import kf-gins --imu nope.txt --truth truth.nav --out kf
LEFT="kf" t import-rate-nan 2 "--rate: .*'nan'" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --rate nan --out kf
LEFT="kf" t import-rate-negative 2 "--rate: .*'-100'" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --rate -100 --out kf
LEFT="kf" t import-mounting-two 2 "--mounting-rpy" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --mounting-rpy 1,2 --out kf
LEFT="kf" t import-mounting-nan 2 "--mounting-rpy: .*'nan'" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --mounting-rpy 0,nan,0 --out kf
LEFT="kf" t import-lever-inf 2 "--lever-arm: .*'inf'" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --lever-arm 0,0,inf --out kf
LEFT="kf" t import-sigma-zero 2 "--ref-sigma-pos: .*'0'" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --ref-sigma-pos 0 --out kf
printf '1.00 0 0 0 0 0 0\n1.01 0 0\n1.02 0 0 0 0 0 0\n' > imu-short.txt
LEFT="kf" t import-imu-short-row 2 "imu-short\.txt:2" "$CALBENCH" import kf-gins --imu imu-short.txt --truth truth.nav --out kf
LEFT="kf" t import-truth-empty 2 "empty\.txt: no truth rows" "$CALBENCH" import kf-gins --imu imu.txt --truth empty.txt --out kf
LEFT="kf" t import-gnss-empty 2 "empty\.txt: no GNSS fixes" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --gnss empty.txt --out kf
LEFT="kf" t import-truth-binary 2 "garbage\.bin:1: 'column 1': not a number: '[ -~]*'$" "$CALBENCH" import kf-gins --imu imu.txt --truth garbage.bin --out kf
printf '1.00 30 114 20 1 1 1\n1.01 30 114 20 1.7e308 1 1\n' > huge.pos
LEFT="kf" t import-gnss-huge 2 "huge\.pos:2: 'column 5': .*1\.7e\+308 outside \[0, " "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --gnss huge.pos --out kf
printf '0 1.00 95.5 114 20 0 0 0 0 0 0\n' > badlat.nav
LEFT="kf" t import-truth-latitude 2 "badlat\.nav:1: 'column 3': latitude \(deg\) 95\.5 outside \[-90, 90\]" "$CALBENCH" import kf-gins --imu imu.txt --truth badlat.nav --out kf
t import-out-is-file 2 "empty\.txt: is a file, not a folder" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --out empty.txt

# ---------------------------------------------------------------------------------- issue 35
# convert: a recording.h5 that cannot be read fully is refused, nothing written (it once gave a
# folder of meta.json "complete" and no tables, exit 0).
ok "$CALBENCH" convert rec --to h5 --out rech5
mkdir trunc zero && cp rech5/meta.json rech5/truth.json trunc/ && cp rech5/meta.json rech5/truth.json zero/
head -c $(( $(stat -c %s rech5/recording.h5) / 2 )) rech5/recording.h5 > trunc/recording.h5
: > zero/recording.h5
LEFT="tc .tc.partial-*" t convert-h5-truncated 2 "^calbench: error: trunc/recording\.h5: cannot open as HDF5 \(damaged or truncated file\)$" "$CALBENCH" convert trunc --to csv --out tc
LEFT="tc .tc.partial-*" t convert-h5-empty 2 "^calbench: error: zero/recording\.h5: not an HDF5 file" "$CALBENCH" convert zero --to csv --out tc
# convert checks time order as every reader does: backwards or repeated stamps in each table.
n=0
for tab in imu reference gnss; do
  for how in back dup; do
    n=$((n + 1))
    mkrec "o$n"
    # Data line 6 (after the '#' comment and the header: line 8 of the file) gets the time of line
    # 7 (dup) or a time before it (back).
    t7=$(sed -n 7p "o$n/$tab.csv" | cut -d, -f1)
    [ $how = dup ] && t8=$t7 || t8=$(echo "$t7 - 0.5" | bc -l)
    sed -i "8s/^[^,]*,/$t8,/" "o$n/$tab.csv"
    [ $how = dup ] && msg="duplicated time" || msg="time goes backwards"
    LEFT="oc .oc.partial-*" t "convert-$tab-$how" 2 "o$n/$tab\.csv:8: 't_s': $msg" "$CALBENCH" convert "o$n" --to h5 --out oc
  done
done
# '+-1' was read as -1 by every CSV reader and by the KF-GINS importer (exit 0): one sign at most.
for num in '+-1' '-+1' '++1' '--1'; do
  mkrec pm
  sed -i "10s/^\([^,]*\),[^,]*,/\1,$num,/" pm/imu.csv
  re=$(printf '%s' "$num" | sed 's/+/\\+/g')
  LEFT="r.json" t "fit-drive-number-$num" 2 "^calbench: error: pm/imu\.csv:10: 'gx_rad_s': not a number: '$re'$" "$CALBENCH" fit drive pm --out r.json
  LEFT="pmc .pmc.partial-*" t "convert-number-$num" 2 "pm/imu\.csv:10: 'gx_rad_s': not a number: '$re'$" "$CALBENCH" convert pm --to h5 --out pmc
  printf '1.00 0 0 0 0 0 0\n1.01 0 %s 0 0 0 0\n1.02 0 0 0 0 0 0\n' "$num" > imu-sign.txt
  LEFT="kf" t "import-number-$num" 2 "^calbench: error: imu-sign\.txt:2: 'column 3': not a number: '$re" "$CALBENCH" import kf-gins --imu imu-sign.txt --truth truth.nav --out kf
done
printf '1.00 0 0 0 0 0 0\n1.7e308 0 0 0 0 0 0\n' > imu-time.txt
LEFT="kf" t import-time-1.7e308 2 "^calbench: error: imu-time\.txt:2: 'time': time 1\.7e\+308 s is not plausible \(at most 1e\+10 s\)$" "$CALBENCH" import kf-gins --imu imu-time.txt --truth truth.nav --out kf
# Options and --inject values through the same parser (common/number_parse.hpp).
LEFT="r.json" t fit-drive-window-plus-minus 2 "--window: expected T0:T1 \(finite seconds\), got '\+-1:5'" "$CALBENCH" fit drive rec --out r.json --window +-1:5
LEFT="s2" t sim-drive-inject-plus-minus 2 "'value': not a number: '\+-1'" "$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --inject time_offset:value=+-1 --until 1 --out s2
LEFT="s2" t sim-drive-until-plus-minus 2 "--until: expected a finite number > 0, got '\+-1'" "$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --until +-1 --out s2
# convert copies a recording: an imu.csv whose last line has no line end (cut by a copy) is refused,
# naming file and line and what to do, nothing written (it once warned, exited 0 and wrote a
# "complete" recording; --json said nothing). fit reads the same file with a warning.
mkrec cut && n=$(wc -l < cut/imu.csv) && head -c -7 cut/imu.csv > cut/imu.cut && mv cut/imu.cut cut/imu.csv
LEFT="cutc .cutc.partial-*" t convert-csv-cut-last-line 2 "^calbench: error: cut/imu\.csv:$n: last line has no line end: .*remove the partial last line.*fit/diagnose read it" "$CALBENCH" convert cut --to h5 --out cutc
LEFT="cutc .cutc.partial-*" t convert-csv-cut-last-line-json 2 "cut/imu\.csv:$n: last line has no line end" "$CALBENCH" convert cut --to h5 --out cutc --json
mkrec pm && sed -i "10s/^\([^,]*\),[^,]*,/\1,+1e-3,/" pm/imu.csv  # one '+' is a sign: read
t convert-number-plus-one 0 NONE "$CALBENCH" convert pm --to h5 --out pmc
rm -rf pmc
# Absurd but finite input is bad input (exit 2, the field), not "filter broke down" (exit 1).
mkrec lever
python3 -c "import json; m = json.load(open('lever/meta.json')); m['mounting']['lever_arm_m'] = [1e15, 0, 0]; json.dump(m, open('lever/meta.json', 'w'))"
LEFT="r.json" t fit-drive-lever-1e15 2 "lever/meta\.json: 'mounting\.lever_arm_m': lever arm of 1e\+15 m is not plausible \(\|r\| at most 100 m\)" "$CALBENCH" fit drive lever --out r.json
mkrec rpy
python3 -c "import json; m = json.load(open('rpy/meta.json')); m['mounting']['rpy_deg'] = [0, 1e9, 0]; json.dump(m, open('rpy/meta.json', 'w'))"
LEFT="r.json" t fit-drive-mounting-1e9 2 "rpy/meta\.json: 'mounting\.rpy_deg\[1\]': 1000000000° is not a mounting angle \(at most ±360°\)" "$CALBENCH" fit drive rpy --out r.json
mkrec tbig
last=$(tail -n 1 tbig/imu.csv); echo "1.7e308,${last#*,}" >> tbig/imu.csv
LEFT="r.json" t fit-drive-time-1.7e308 2 "tbig/imu\.csv:$(wc -l < tbig/imu.csv): 't_s': time 1\.7e\+308 s is not plausible \(at most 1e\+10 s\)" "$CALBENCH" fit drive tbig --out r.json
mkrec tgap
last=$(tail -n 1 tgap/imu.csv); echo "9000,${last#*,}" >> tgap/imu.csv
LEFT="r.json" t fit-drive-imu-gap 2 "tgap/imu\.csv:$(wc -l < tgap/imu.csv): 't_s': [0-9.]+ s after the row before: not an IMU interval \(at most 3600 s" "$CALBENCH" fit drive tgap --out r.json
mkrec wbig && sed -i "12s/^\([^,]*\),[^,]*,/\1,-2e4,/" wbig/imu.csv
LEFT="r.json" t fit-drive-rate-2e4 2 "wbig/imu\.csv:12: 'gx_rad_s': angular rate -20000 rad/s is not plausible \(at most 10000 rad/s\)" "$CALBENCH" fit drive wbig --out r.json
mkrec fbig && sed -i "12s/^\(\([^,]*,\)\{6\}\)[^,]*/\11e6/" fbig/imu.csv
LEFT="r.json" t fit-drive-force-1e6 2 "fbig/imu\.csv:12: 'az_m_s2': specific force 1000000 m/s² is not plausible \(at most 100000 m/s²\)" "$CALBENCH" fit drive fbig --out r.json
# A multi-unit fit in which every unit fails leaves nothing: no OUT/units.json, no slot folders.
ok "$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 4 --until 12 --units 2 --out mu
sed -i '30s/^\([^,]*\),[^,]*,/\1,x,/' mu/1/imu.csv mu/2/imu.csv
LEFT="muo" t fit-drive-units-all-fail 2 "unit 2: mu/2/imu\.csv:30: 'gx_rad_s': not a number: 'x'.*|no unit fitted: nothing written under muo" "$CALBENCH" fit drive mu --out muo
grep -q "no unit fitted: nothing written under muo" "$T/err.txt" || FAILED+=("fit-drive-units-all-fail: no 'nothing written' line")
mkdir muo2
t fit-drive-units-all-fail-existing 2 "no unit fitted: nothing written under muo2" "$CALBENCH" fit drive mu --out muo2
[ -z "$(ls -A muo2)" ] || FAILED+=("fit-drive-units-all-fail-existing: left $(ls -A muo2 | tr '\n' ' ')in muo2")
# fit drive on a cut imu.csv (item 7): the truncation said once, what to do, and no '--from'.
mkrec tcsv
{ head -n 3000 rec/imu.csv; printf '15.0,0.01'; } > tcsv/imu.csv  # cut in its last line; the reference goes on
t fit-drive-cut-imu 0 "tcsv/imu\.csv:3001: last line has no line end: treated as truncated and not used .*if the file was cut short by a copy, copy it again" "$CALBENCH" fit drive tcsv --out r.json
[ "$(grep -c "last line has no line end" "$T/err.txt")" = 1 ] || FAILED+=("fit-drive-cut-imu: the truncation warning is not said exactly once")
grep -q -- "--from" "$T/err.txt" && FAILED+=("fit-drive-cut-imu: names --from, an option never given")
rm -f r.json

# ---------------------------------------------------------------------------------- read-only --out
# A folder nobody may write to: permissions where they hold (not root), else a read-only tmpfs.
mkdir ro
chmod 555 ro
if ! touch ro/probe 2> /dev/null; then :
elif rm -f ro/probe && mount -t tmpfs -o ro,size=1m tmpfs ro 2> /dev/null; then RO_MOUNTED=1
else rm -f ro/probe; SKIPPED+=("read-only --out (no read-only folder can be made here)"); fi
if [ ${#SKIPPED[@]} = 0 ]; then
  t ro-fit-bench-out 2 "ro/c\.json: cannot write into the folder ro: (Read-only file system|Permission denied)" "$CALBENCH" fit bench bench --out ro/c.json
  t ro-db-export-out 2 "ro/e\.json: cannot write into the folder ro" "$CALBENCH" db export 2 --db d.db --out ro/e.json
  t ro-simulate-out 2 "ro/s: cannot write into ro" "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --out ro/s
  t ro-station-out 2 "not started \(nothing ran\): ro/st: cannot write into ro" "$CALBENCH" station run --emulated --plan "$SRC/tests/data/short_plan.toml" --out ro/st
  t ro-import-out 2 "ro/kf: cannot write into ro" "$CALBENCH" import kf-gins --imu imu.txt --truth truth.nav --out ro/kf
  t ro-db-init 2 "ro/x\.db: cannot create the database in ro: (Read-only file system|Permission denied)" "$CALBENCH" db init --db ro/x.db
fi

# ---------------------------------------------------------------------------------- result
for s in "${SKIPPED[@]}"; do echo "bad_input_suite: skipped: $s"; done
if [ ${#FAILED[@]} -gt 0 ]; then
  echo "bad_input_suite: ${#FAILED[@]} case(s) FAILED, $PASSED passed:" >&2
  printf '  %s\n' "${FAILED[@]}" >&2
  exit 1
fi
echo "$PASSED cases passed"
