#!/usr/bin/env bash
# Issue 36, acceptance 2: clean simulated recordings through `calbench diagnose --json`, counting
# established findings (the target is 0), partial findings, unexplained axes and drift notes (not findings;
# their names are listed with the rest, "… drift noted").
# Bench: CLEAN_BENCH recordings (default 100), plans in turn from CLEAN_PLANS (default "diagnose factory
# wedge"), --truth random. Drive: CLEAN_DRIVE recordings (default 100), routes in turn from CLEAN_ROUTES
# (default: tests/data/drive_diag_route.toml, tests/data/drive_diag_level.toml, bench/routes/short.toml),
# device classes in turn from CLEAN_CLASSES (default "adis16488a adis16465-1 icm42688p"), --truth random,
# no --coeffs (bias and M fitted on the drive). Seeds 5000+i (bench) and 6000+i (drive).
# Prints one line per recording (kind, source, seed, seconds, counts), then the summary; writes it,
# stamped, to docs/validation/diagnose-clean-runs.md (VALIDATION_NAME=OTHER.md).
# Usage: bench/diagnose/clean_runs.sh [BUILD_DIR]
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
command="$(env | { grep -E '^CLEAN_' || true; } | sort | tr '\n' ' ')bench/diagnose/clean_runs.sh $*"
BUILD=$(cd "${1:-build}" && pwd)
cb="$BUILD/calbench"
work=$(mktemp -d /tmp/clean_runs.XXXXXX)
trap 'rm -rf "$work"' EXIT
read -r -a plans <<< "${CLEAN_PLANS:-diagnose factory wedge}"
read -r -a routes <<< "${CLEAN_ROUTES:-tests/data/drive_diag_route.toml tests/data/drive_diag_level.toml bench/routes/short.toml}"
read -r -a classes <<< "${CLEAN_CLASSES:-adis16488a adis16465-1 icm42688p}"
log="${CLEAN_RUNS:-$work/runs.tsv}"
one() {  # KIND SOURCE SEED DIR [diagnose args]
  local kind=$1 src=$2 seed=$3 dir=$4 t0 t1
  shift 4
  t0=$(date +%s.%N)
  "$cb" diagnose "$dir" --json "$@" > "$work/out.json"
  t1=$(date +%s.%N)
  python3 - "$kind" "$src" "$seed" "$(echo "$t1 - $t0" | bc)" "$work/out.json" <<'PY' | tee -a "$log"
import json, sys
kind, src, seed, sec, path = sys.argv[1:]
d = json.load(open(path))
est = [f"{f['effect']} {f['sensor']} {f['axis']}" for f in d["findings"] if f.get("established")]
par = [f"{f['effect']} {f['sensor']} {f['axis']}" for f in d["findings"] if not f.get("established")]
par += [f"drift beyond stability {x['sensor']} {x['axis']}" for x in d.get("drift_excess", [])]
une = [f"{u['sensor']} {u['axis']}" for u in d["unexplained"]]
sat = [f"{x['sensor']} {x['axis']} range exceeded" for x in d.get("saturation", [])]
note = [f"{x['sensor']} {x['axis']} drift noted" for x in d.get("drift_noted", [])]
lo = d.get("low_input") or {}
low = [f"gyro {x['axis']} smallest inputs {lo['verdict']}" for x in lo.get("axes", [])] if lo.get("verdict") in ("not sensed", "cannot tell") else []
print("\t".join([kind, src, seed, f"{float(sec):.1f}", str(len(est)), str(len(par)), str(len(une)), "; ".join(est + [p + " (partial)" for p in par] + [u + " unexplained" for u in une] + sat + low + note), str(len(note))]))
PY
}
# CLEAN_TABLE_ONLY=1: no new runs, the table from the per-run file already there (a run stopped early).
if [ -z "${CLEAN_TABLE_ONLY:-}" ]; then
: > "$log"
for i in $(seq 0 $((${CLEAN_BENCH:-100} - 1))); do
  plan=${plans[$((i % ${#plans[@]}))]}
  t0=$(date +%s.%N)
  "$cb" simulate bench --plan "$here/bench/plans/$plan.toml" --truth random --seed $((5000 + i)) --out "$work/rec" --force >/dev/null
  one bench "$plan (sim $(echo "$(date +%s.%N) - $t0" | bc | cut -c1-4) s)" $((5000 + i)) "$work/rec"
done
for i in $(seq 0 $((${CLEAN_DRIVE:-100} - 1))); do
  route=${routes[$((i % ${#routes[@]}))]}
  class=${classes[$((i % ${#classes[@]}))]}
  "$cb" simulate drive --route "$here/$route" --device-class "$class" --truth random --seed $((6000 + i)) --out "$work/rec" --force >/dev/null
  one drive "$(basename "$route") $class" $((6000 + i)) "$work/rec"
done
fi
md="$work/table.md"
python3 - "$log" > "$md" <<'PY'
import sys, collections
rows = collections.OrderedDict()
for line in open(sys.argv[1]):
    kind, src, seed, sec, e, p, u, names, notes = (line.rstrip("\n").split("\t") + ["", "0"])[:9]
    key = (kind, src.split(" (sim")[0])
    rows.setdefault(key, []).append((int(e), int(p), int(u), float(sec), names, int(notes or 0)))
tot = collections.Counter()
print("| kind | plan / route, class | recordings | established findings | recordings with one | partial findings | unexplained axes | drift notes (not findings) | diagnose s per recording (median) | what was named |")
print("|---|---|---|---|---|---|---|---|---|---|")
for (kind, src), rs in rows.items():
    n = len(rs); e = sum(r[0] for r in rs); p = sum(r[1] for r in rs); u = sum(r[2] for r in rs)
    secs = sorted(r[3] for r in rs)
    names = collections.Counter(x for r in rs for x in r[4].split("; ") if x)
    tot[kind, "n"] += n; tot[kind, "e"] += e; tot[kind, "r"] += sum(1 for r in rs if r[0])
    tot[kind, "notes"] += sum(r[5] for r in rs); tot[kind, "noted"] += sum(1 for r in rs if r[5])
    print(f"| {kind} | {src} | {n} | {e} | {sum(1 for r in rs if r[0])} | {p} | {u} | {sum(r[5] for r in rs)} | {secs[len(secs)//2]:.1f} | {', '.join(f'{k} ({v})' for k, v in sorted(names.items())) or '–'} |")
print()
for kind in ("bench", "drive"):
    if tot[kind, "n"]:
        print(f"**Clean {kind} recordings: {tot[kind, 'n']}, established findings {tot[kind, 'e']} (in {tot[kind, 'r']} recordings).**"
              f" Drift notes (not findings): {tot[kind, 'notes']} in {tot[kind, 'noted']} recordings.")
        print()
PY
cat "$md"
{
  echo "Clean simulated recordings (no injected effect) through \`calbench diagnose --json\`; the issue-36 target is"
  echo "0 established findings. \"partial findings\" include a drift beyond the class's stability (reported, never"
  echo "established); a plateau (range exceeded) is listed by name. \"drift notes\": the drift model absorbed a"
  echo "bias change beyond 2× the class's stability that its own drift also makes (a note, not a finding: on a"
  echo "clean unit it is the class's drift). \"smallest inputs not sensed\" (a false alarm on a clean unit) or"
  echo "\"cannot tell\" are listed by name.${CLEAN_NOTE:+ $CLEAN_NOTE}"
  echo
  cat "$md"
} | "$here/scripts/validation-stamp" "${VALIDATION_NAME:-diagnose-clean-runs.md}" \
      "Clean recordings through the diagnosis (\`bench/diagnose/clean_runs.sh\`)" "$command"
