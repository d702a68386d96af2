#!/usr/bin/env bash
# fit drive --series → identify → fit drive --drift-models, with no hand editing (issue 6): identify
# picks the total-drift columns of an in-motion series, converts °/h and mg to SI and names sensor
# and axis; fit drive assigns the models per axis, keeps the data-sheet default where a model is
# missing, converts units a hand-written file states, and rejects what it cannot place.
set -euo pipefail
: "${CALBENCH:?}" "${SRC:?}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 5 --out "$tmp/d" >/dev/null
"$CALBENCH" fit drive "$tmp/d" --window 0:200 --out "$tmp/r0.json" --series "$tmp/s.csv" >/dev/null
head -2 "$tmp/s.csv" | grep -q "gyro_total_x_dph" || fail "series lacks the total drift columns"
jq -e 'has("drift_models") | not' "$tmp/r0.json" >/dev/null || fail "drift_models reported without --drift-models"

# identify: by default the six total-drift columns, in SI, with sensor and axis.
"$CALBENCH" identify "$tmp/s.csv" --from 60 --no-allan --json --out "$tmp/m.json" > "$tmp/id.json"
jq -e '[.columns[].column] == ["gyro_total_x_dph","gyro_total_y_dph","gyro_total_z_dph","accel_total_x_mg","accel_total_y_mg","accel_total_z_mg"]' \
  "$tmp/id.json" >/dev/null || fail "default columns: $(jq -c '[.columns[].column]' "$tmp/id.json")"
jq -e '.columns[0] | .sensor == "gyro" and .axis == 0 and .unit == "rad/s" and .converted_from == "deg/h"' "$tmp/id.json" >/dev/null \
  || fail "gyro x column: $(jq -c '.columns[0] | {sensor, axis, unit, converted_from}' "$tmp/id.json")"
jq -e '.columns[5] | .sensor == "accel" and .axis == 2 and .unit == "m/s^2" and .converted_from == "mg"' "$tmp/id.json" >/dev/null \
  || fail "accel z column"
# σ in SI: no larger than the column's standard deviation converted (°/h → rad/s, mg → m/s²),
# and not smaller than a hundredth of it (a unit slip is a factor 10^5 / 10^2).
awk -F, -v k=gyro_total_x_dph -v from=60 'BEGIN{c=0} /^#/{next} !c{for(i=1;i<=NF;i++) if($i==k) c=i; next}
  $1>=from {n++; s+=$c; q+=$c*$c} END{printf "%.12g\n", sqrt(q/n-(s/n)^2)*3.141592653589793/180/3600}' "$tmp/s.csv" > "$tmp/std"
jq -e --argjson sd "$(cat "$tmp/std")" '.drift_models.gyro_total_x_dph | .sigma <= 1.01 * $sd and .sigma > 0.01 * $sd and .unit == "rad/s"' \
  "$tmp/m.json" >/dev/null || fail "gyro x sigma not in rad/s: $(jq '.drift_models.gyro_total_x_dph.sigma' "$tmp/m.json") vs std $(cat "$tmp/std")"

# fit drive with the models: every axis from the file, σ back in °/h matches.
"$CALBENCH" fit drive "$tmp/d" --window 0:200 --out "$tmp/r1.json" --drift-models "$tmp/m.json" > "$tmp/r1.txt"
grep -q "drift model gyro x" "$tmp/r1.txt" || fail "summary lacks the drift models"
jq -e '.drift_models.axes | length == 6 and all(.source | startswith("drift_models."))' "$tmp/r1.json" >/dev/null \
  || fail "all six axes should come from the file: $(jq -c '[.drift_models.axes[].source]' "$tmp/r1.json")"
jq -e --slurpfile m "$tmp/m.json" '(.drift_models.axes[0].sigma_si - $m[0].drift_models.gyro_total_x_dph.sigma | fabs) < 1e-15' \
  "$tmp/r1.json" >/dev/null || fail "gyro x sigma changed on the way"
jq -e '.consistency.attitude.epochs > 1000' "$tmp/r1.json" >/dev/null || fail "no fit"

# A hand-written file: one exp-cosine gyro model in °/h (explicit sensor/axis), one accel model
# keyed by its recording column in SI; the rest keep the data-sheet default.
cat > "$tmp/hand.json" <<'EOF'
{"drift_models": {
  "my_gyro": {"model": "exp_cosine", "sensor": "gyro", "axis": 1, "unit": "deg/h", "sigma": 12.0, "alpha": 0.02, "beta": 0.05},
  "az_m_s2": {"model": "exponential", "sigma": 0.002, "alpha": 0.01}}}
EOF
"$CALBENCH" fit drive "$tmp/d" --window 0:200 --out "$tmp/r2.json" --drift-models "$tmp/hand.json" >/dev/null
jq -e '.drift_models.layout | startswith("augmented")' "$tmp/r2.json" >/dev/null || fail "exp-cosine needs the augmented layout"
jq -e '.drift_models.axes[1] | .model == "exp_cosine" and (.sigma - 12 | fabs) < 1e-9 and (.sigma_si - 12*3.141592653589793/180/3600 | fabs) < 1e-15 and .beta_rad_s == 0.05' \
  "$tmp/r2.json" >/dev/null || fail "gyro y: $(jq -c '.drift_models.axes[1]' "$tmp/r2.json")"
jq -e '.drift_models.axes[5] | .source == "drift_models.az_m_s2" and .sigma_si == 0.002 and .T_s == 100' "$tmp/r2.json" >/dev/null \
  || fail "accel z: $(jq -c '.drift_models.axes[5]' "$tmp/r2.json")"
jq -e '[.drift_models.axes[0,2,3,4].source] | all(startswith("data-sheet default"))' "$tmp/r2.json" >/dev/null \
  || fail "missing axes must keep the data-sheet default"
jq -e '.consistency.attitude.mean_nis > 0.3 and .consistency.attitude.mean_nis < 10' "$tmp/r2.json" >/dev/null \
  || fail "augmented fit inconsistent: $(jq -c .consistency "$tmp/r2.json")"

# What cannot be placed is an input error (exit 2) naming the key.
expect_error() {  # file, text expected in the message
  set +e
  "$CALBENCH" fit drive "$tmp/d" --window 0:200 --out "$tmp/bad.json" --drift-models "$1" 2> "$tmp/err"
  rc=$?
  set -e
  [ "$rc" -eq 2 ] || fail "exit $rc, expected 2 for $1"
  grep -q -- "$2" "$tmp/err" || fail "message lacks '$2': $(cat "$tmp/err")"
}
echo '{"drift_models": {"temperature": {"model": "exponential", "sigma": 1, "alpha": 0.1}}}' > "$tmp/b1.json"
expect_error "$tmp/b1.json" "drift_models.temperature"
echo '{"drift_models": {"ax_m_s2": {"model": "exponential", "unit": "deg/h", "sigma": 1, "alpha": 0.1}}}' > "$tmp/b2.json"
expect_error "$tmp/b2.json" "does not fit sensor"
echo '{"drift_models": {"gx_rad_s": {"model": "exponential", "sigma": 1e-5, "alpha": 0.1},
                        "gyro_total_x_dph": {"model": "exponential", "sigma": 2, "alpha": 0.1}}}' > "$tmp/b3.json"
expect_error "$tmp/b3.json" "second model for gyro axis x"
[ ! -e "$tmp/bad.json" ] || fail "RESULT.json written despite the error"
echo "ok"
