#!/usr/bin/env bash
# Issue 36: confusion rows for effects made by the independent injector (bench/diagnose/inject_effects.py),
# not by calbench's simulator hooks. Each seed: a clean recording simulated by calbench, the effect added
# by the injector, then `calbench diagnose --json`; each run is scored as
#   established: a finding with "established": true (its names listed; for a term outside the
#                catalogue any established name is wrong; for warm-up the temperature term is right),
#   partial:     findings, none established (not told apart from an alternative),
#   unexplained: an axis reported as unexplained,  range exceeded, bias change beyond 3σ (drives),
#   smallest inputs not sensed: the low-input test (JSON low_input) found the gyro output does not
#                follow its smallest inputs (a dead band or threshold, outside the catalogue),
#   noted only:  none of these, but a drift note (drift_noted: not a finding),
#   nothing said: none of these and no note.
# Bench rows: the diagnosis plan (bench/plans/diagnose.toml; INJECT_PLANS="diagnose factory" for more),
# then the rows of INJECT_EXTRA_PLAN (default lowrate, bench/plans/lowrate.toml: clean and the dead band).
# Drive rows: the level test route tests/data/drive_diag_level.toml (every grade 0, f_z ≈ −g), diagnosed
# with the bench fit of the same simulated unit on the diagnosis plan (--coeffs), so the injected change is
# the only change since the bench.
# Writes docs/validation/diagnose-inject-confusion.md (VALIDATION_NAME=OTHER.md), stamped.
# Usage: bench/diagnose/inject_confusion.sh [BUILD_DIR]     env: INJECT_SEEDS (default 5), INJECT_PLANS,
#   INJECT_EXTRA_PLAN, INJECT_KINDS (bench, drive or both; with it the runs are appended to INJECT_RUNS)
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
command="$(env | { grep -E '^INJECT_' || true; } | sort | tr '\n' ' ')bench/diagnose/inject_confusion.sh $*"
BUILD=$(cd "${1:-build}" && pwd)
cb="$BUILD/calbench"
inj="$here/bench/diagnose/inject_effects.py"
seeds=${INJECT_SEEDS:-5}
work=$(mktemp -d /tmp/inject_confusion.XXXXXX)
trap 'rm -rf "$work"' EXIT
runs="${INJECT_RUNS:-$work/runs.tsv}"
score() {  # ROW JSON -> one TSV line: row, established names, partial names, unexplained axes
  python3 - "$1" "$2" >> "$runs" <<'PY'
import json, sys
row, path = sys.argv[1], sys.argv[2]
d = json.load(open(path))
est = sorted({f"{f['effect']} {f['sensor']} {f['axis']}" for f in d["findings"] if f.get("established")})
par = sorted({f"{f['effect']} {f['sensor']} {f['axis']}" for f in d["findings"] if not f.get("established")} |
             {f"drift beyond stability {x['sensor']} {x['axis']}" for x in d.get("drift_excess", [])})
une = sorted({f"{u['sensor']} {u['axis']}" for u in d["unexplained"]})
sat = sorted({f"{x['sensor']} {x['axis']}" for x in d.get("saturation", [])})
bias = sorted(a.replace("_", " ") for a in d.get("bias_since_coefficients", {}).get("beyond_3sigma", []))
note = sorted({f"{x['sensor']} {x['axis']}" for x in d.get("drift_noted", [])})
lo = d.get("low_input") or {}
low = sorted({f"{lo['verdict']} gyro {x['axis']}" for x in lo.get("axes", [])}) if lo.get("verdict") in ("not sensed", "cannot tell") else []
# Drives: the largest figure of the remainder's condition test over the axes it tested (at or above its
# level the axis is unexplained; below, how far the run was from that).
near = max(((v["condition_test"]["delta_chi2"], k, v["condition_test"]["condition"]) for k, v in d["axes"].items()
            if "condition_test" in v), default=None)
near = f"{near[1].replace('_', ' ')} {near[2]} {near[0]:.3g}" if near else ""
print("\t".join([row, "; ".join(est), "; ".join(par), "; ".join(une), "; ".join(sat), "; ".join(bias), "; ".join(note), "; ".join(low), near]))
PY
}
bench_classes=(
  "clean (no injection)|"
  "warm-up gyro z, 20 °/h over 10 °C|warmup --sensor gyro --axis z --change 20 --dT 10"
  "warm-up gyro z, 40 °/h over 10 °C|warmup --sensor gyro --axis z --change 40 --dT 10"
  "warm-up accel x, 1 mg over 10 °C|warmup --sensor accel --axis x --change 1 --dT 10"
  "dead band gyro xyz, 0.01 °/s|deadband --axis all --width 0.01"
  "rotation memory gyro z, 30 °/h|memory --axis z --memory 30"
  "saturation gyro z, 97 % of the top rate|saturation --axis z"
)
# Rows on a plan of their own (INJECT_EXTRA_PLAN, default the low-rate plan: a dead band needs inputs
# inside it), after the INJECT_PLANS rows.
extra_plan=${INJECT_EXTRA_PLAN:-lowrate}
extra_classes=(
  "clean (no injection)|"
  "dead band gyro xyz, 0.01 °/s|deadband --axis all --width 0.01"
)
drive_classes=(
  "speed-dependent bias gyro z, 1 °/h per m/s|speed --sensor gyro --axis z --k 1"
  "speed-dependent bias gyro z, 2 °/h per m/s|speed --sensor gyro --axis z --k 2"
  "speed-dependent bias gyro z, 3 °/h per m/s|speed --sensor gyro --axis z --k 3"
  "turn-on bias shift gyro x, 30 °/h|shift --sensor gyro --axis x --bias 30"
)
# INJECT_TABLE_ONLY=1: no new runs, the table from the per-run file already there (a run stopped early).
if [ -z "${INJECT_TABLE_ONLY:-}" ]; then
[ -n "${INJECT_KINDS:-}" ] || : > "$runs"
kinds=${INJECT_KINDS:-bench drive}  # INJECT_KINDS=drive: the drive rows only (appended to INJECT_RUNS)
bench_rows() {  # PLAN SEED CLASS...: one clean recording of the plan, each class injected into it and diagnosed
  local plan=$1 seed=$2 c
  shift 2
  "$cb" simulate bench --plan "$here/bench/plans/$plan.toml" --truth random --seed "$seed" --out "$work/clean" --force >/dev/null
  for c in "$@"; do
    if [ -n "${c#*|}" ]; then
      # shellcheck disable=SC2086
      python3 "$inj" "$work/clean" "$work/inj" ${c#*|} --force
    else
      rm -rf "$work/inj"; cp -r "$work/clean" "$work/inj"
    fi
    "$cb" diagnose "$work/inj" --json > "$work/out.json"
    score "bench $plan: ${c%%|*}" "$work/out.json"
  done
}
if [[ " $kinds " == *" bench "* ]]; then
  for plan in ${INJECT_PLANS:-diagnose}; do
    for s in $(seq 1 "$seeds"); do bench_rows "$plan" "$((3600 + s))" "${bench_classes[@]}"; done
  done
  if [ -n "$extra_plan" ]; then
    for s in $(seq 1 "$seeds"); do bench_rows "$extra_plan" "$((3600 + s))" "${extra_classes[@]}"; done
  fi
fi
for s in $(seq 1 "$seeds"); do
  [[ " $kinds " == *" drive "* ]] || break
  "$cb" simulate drive --route "$here/tests/data/drive_diag_level.toml" --truth random --seed "$((3700 + s))" --out "$work/drive" --force >/dev/null
  "$cb" simulate bench --plan "$here/bench/plans/diagnose.toml" --truth "$work/drive/truth.json" --seed "$((3800 + s))" --out "$work/bench" --force >/dev/null
  "$cb" fit bench "$work/bench" --out "$work/bench.json" >/dev/null
  for c in "clean (no injection)|" "${drive_classes[@]}"; do
    row="drive level: ${c%%|*}"
    if [ -n "${c#*|}" ]; then
      # shellcheck disable=SC2086
      python3 "$inj" "$work/drive" "$work/inj" ${c#*|} --force
    else
      rm -rf "$work/inj"; cp -r "$work/drive" "$work/inj"
    fi
    "$cb" diagnose "$work/inj" --coeffs "$work/bench.json" --json > "$work/out.json"
    score "$row" "$work/out.json"
  done
done
fi
md="$work/table.md"
python3 - "$runs" > "$md" <<'PY'
import sys, collections
rows = collections.OrderedDict()
for line in open(sys.argv[1]):
    row, est, par, une, sat, bias, note, low, near = (line.rstrip("\n").split("\t") + [""] * 8)[:9]
    rows.setdefault(row, []).append((est, par, une, sat, bias, low, note, near))
print("| injected (by inject_effects.py) | runs | established (any) | partial only | unexplained (any) | range exceeded | bias change beyond 3σ | smallest inputs not sensed or not told apart | noted only (not a finding) | nothing said | established names (runs) | partial names (runs) | unexplained axes (runs) | range exceeded (runs) | bias change since --coeffs beyond 3σ (runs) | smallest inputs (runs) | drift noted (runs) | largest condition test Δχ² (drives, per run; unexplained at ≥ 19.1) |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
def tally(xs):
    c = collections.Counter(n for x in xs for n in x.split("; ") if n)
    return ", ".join(f"{k} ({v})" for k, v in sorted(c.items())) or "–"
for row, rs in rows.items():
    n = len(rs)
    e = sum(1 for r in rs if r[0]); p = sum(1 for r in rs if not r[0] and r[1]); u = sum(1 for r in rs if r[2])
    x = sum(1 for r in rs if r[3]); b = sum(1 for r in rs if r[4])
    lo = sum(1 for r in rs if r[5])
    o = sum(1 for r in rs if r[6] and not any(r[:6])); z = sum(1 for r in rs if not any(r[:7]))
    near = ", ".join(r[7] for r in rs if r[7]) or "–"
    print(f"| {row} | {n} | {e} | {p} | {u} | {x} | {b} | {lo} | {o} | {z} | {tally(r[0] for r in rs)} | {tally(r[1] for r in rs)} | {tally(r[2] for r in rs)} | {tally(r[3] for r in rs)} | {tally(r[4] for r in rs)} | {tally(r[5] for r in rs)} | {tally(r[6] for r in rs)} | {near} |")
PY
cat "$md"
{
  echo "Effects outside calbench's simulator, added by \`bench/diagnose/inject_effects.py\` to clean simulated"
  echo "recordings; \"established\": runs with at least one established finding (for a term outside the catalogue"
  echo "every established name is a wrong name; for warm-up the temperature term on the injected axis is right);"
  echo "\"partial only\": findings, none established; \"unexplained\": runs with an axis reported unexplained;"
  echo "\"partial only\" includes a drift beyond the class's stability (reported, never established); \"range"
  echo "exceeded\": an output plateau found and its steps left out; \"bias change beyond 3σ\" (drives, diagnosed"
  echo "with the unit's bench coefficients): the bias re-estimated on the drive differs from the bench's by more"
  echo "than 3σ, the right answer for a turn-on bias shift (the null alternative); \"noted only\": nothing of"
  echo "these, but a note that the drift model absorbed a bias change beyond 2× the class's stability which the"
  echo "class's own drift also makes (not a finding; it says what it cannot tell apart); \"smallest inputs not"
  echo "sensed\": the gyro output does not follow its smallest rate inputs (a dead band or threshold, outside the"
  echo "catalogue), found and the rest diagnosed with them taken as not sensed, or (\"cannot tell\" in the names"
  echo "column) that reading fits as well as the catalogue's model, whose gyro findings are then not told apart from it;"
  echo "\"nothing said\": none"
  echo "of these (a miss for every row but the clean ones). Last column (drives): per run, the axis and motion"
  echo "condition with the largest Δχ² of the remainder's condition test (GLS under the noise model, χ²₁; at or"
  echo "above 19.1, a false alarm of 10⁻³ per recording, the axis is unexplained; below, it shows how far the run"
  echo "was from that). Axes with a finding or already unexplained by their χ² are not tested."
  [ -z "${INJECT_NOTE:-}" ] || { echo; echo "$INJECT_NOTE"; }
  echo
  cat "$md"
} | "$here/scripts/validation-stamp" "${VALIDATION_NAME:-diagnose-inject-confusion.md}" \
      "Confusion rows for injected effects outside the catalogue (\`bench/diagnose/inject_confusion.sh\`)" "$command"
