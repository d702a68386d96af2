#!/usr/bin/env bash
# diagnose on simulated multipos recordings (bench/multipos/sim_effects.py: physics written out in
# Python, no calbench code), per case and seed: the findings (effect sensor axis status), whether
# each g-sensitivity component lies within 3σ of the truth, the χ²/dof of the touched dataset
# before → after. Prints a Markdown table (docs/validation/diagnose-multipos.md).
#   bench/multipos/diagnose_runs.sh CALBENCH [SEEDS...]     (default seeds 401–420)
set -euo pipefail
CB=${1:?usage: diagnose_runs.sh CALBENCH [SEEDS...]}; shift
seeds=("$@"); [ ${#seeds[@]} -gt 0 ] || seeds=($(seq 401 420))
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
echo "| case | seed | findings (effect sensor axis: status) | g-sens within 3σ | χ²/dof before → after |"
echo "|---|---|---|---|---|"
for case in clean gsens k2; do
  case $case in clean) opt=();; gsens) opt=(--gsens x=0,1.5e-5,0);; k2) opt=(--k2 y=1e-4);; esac
  for s in "${seeds[@]}"; do
    d="$tmp/$case$s"
    python3 "$here/sim_effects.py" "$d.sim" --seed "$s" "${opt[@]}"
    "$CB" import imu-tk "$d.sim/acc.txt" "$d.sim/gyro.txt" --out "$d" --model ADIS16488A --serial "S$s" --site-lat 52 > /dev/null
    "$CB" diagnose "$d" --json > "$d.json"
    python3 - "$d.json" "$case" "$s" <<'PY'
import json, math, sys
j, case, seed = json.load(open(sys.argv[1])), sys.argv[2], sys.argv[3]
fs = "; ".join(f"{f['effect']} {f['sensor']} {f['axis']}: {f['status']}" for f in j["findings"]) or "none"
if j["unexplained"]:
    fs += " + unexplained " + ", ".join(f"{u['sensor']} {u['axis']}" for u in j["unexplained"])
within = ""
if case == "gsens":
    g = [f for f in j["findings"] if f["effect"] == "g_sensitivity" and f["axis"] == "x"]
    if g:
        within = "yes" if all(abs(v - t) <= 3 * s for v, s, t in zip(g[0]["value"], g[0]["sigma"], (0, 1.5e-5, 0))) else "no"
    else:
        within = "not found"
ax = {"clean": None, "gsens": "gyro_x", "k2": "accel_gravity_magnitude"}[case]
chi = "" if ax is None else f"{j['axes'][ax]['before']['chi2_per_dof']:.2f} → {j['axes'][ax]['after']['chi2_per_dof']:.2f}"
print(f"| {case} | {seed} | {fs} | {within} | {chi} |")
PY
  done
done
