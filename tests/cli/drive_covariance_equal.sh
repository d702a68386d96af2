#!/usr/bin/env bash
# The structured covariance arithmetic (the default: the moving rows only) gives what the former
# dense path (--covariance dense: full N x N products every step) gives, within 1e-9 relative on
# every number of RESULT.json and of the --series file (measured: bit for bit): reference aiding
# with all three observations and out-of-sample QC, position only (heading from the course),
# GNSS-only (levelling, re-alignment), the RTS smoother, and the augmented layout of an exp-cosine
# model. The Joseph-form update (--covariance joseph) rounds differently; its results agree with
# the dense path's to the rounding floor of the problem (checked below with its own bound).
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 5 --out "$T/rec" >/dev/null
cat > "$T/models.json" <<'JSON'
{"drift_models": {
  "my_gyro": {"model": "exp_cosine", "sensor": "gyro", "axis": 2, "unit": "deg/h", "sigma": 12.0, "alpha": 0.02, "beta": 0.05}}}
JSON
compare() {  # name, then the fit options
  local name=$1
  shift
  for cov in ${COVS:-structured} dense; do
    "$CALBENCH" fit drive "$T/rec" "$@" --covariance $cov --out "$T/$name.$cov.json" --series "$T/$name.$cov.csv" >/dev/null
  done
  local form=${COVS:-structured}
  python3 - "$T/$name.$form.json" "$T/$name.dense.json" "$T/$name.$form.csv" "$T/$name.dense.csv" "$name" "$form" <<'PY'
# Every number of RESULT.json and of the series, compared output by output: a scalar by its own
# magnitude, an array (a vector, a matrix, a series column over time) norm-wise, |a - b| / |b|
# with the max norm (element by element too, reported). The rounding floor: the dense path differs
# from itself by ~2e-9 norm-wise (~7e-9 element-wise, small skews) when only the association of
# its triple product changes, Phi*(P*Phi^T) for (Phi*P)*Phi^T.
import json, sys, csv, os
a, b = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
form = sys.argv[6]
assert (a.pop("covariance"), b.pop("covariance")) == (form, "dense")
tol = 1e-9 if form == "structured" else 1e-6
worst, worst_el, n = [0.0, ""], [0.0, ""], [0]
def leaves(x):
    return isinstance(x, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) or leaves(v) for v in x)
def flat(x):
    return [w for v in x for w in (flat(v) if isinstance(v, list) else [v])]
def check(xs, ys, path):
    assert len(xs) == len(ys), path
    scale = max([abs(v) for v in xs + ys] + [0.0])
    d = max([abs(u - v) for u, v in zip(xs, ys)] + [0.0])
    rel = 0.0 if d == 0 else d / scale
    n[0] += len(xs)
    if rel > worst[0]: worst[:] = [rel, path]
    for u, v in zip(xs, ys):
        if u != v and abs(u - v) / max(abs(u), abs(v)) > worst_el[0]: worst_el[:] = [abs(u - v) / max(abs(u), abs(v)), path]
    assert rel <= tol, (path, rel, xs[:4], ys[:4])
def cmp(x, y, path):
    if isinstance(x, dict):
        assert isinstance(y, dict) and x.keys() == y.keys(), path
        for k in x: cmp(x[k], y[k], path + "." + k)
    elif isinstance(x, list) and x and leaves(x):
        assert isinstance(y, list), path
        check(flat(x), flat(y), path)
    elif isinstance(x, list):
        assert isinstance(y, list) and len(x) == len(y), path
        for i, (u, v) in enumerate(zip(x, y)): cmp(u, v, f"{path}[{i}]")
    elif isinstance(x, (int, float)) and not isinstance(x, bool):
        check([x], [y], path)
    else:
        assert x == y, (path, x, y)
cmp(a, b, "RESULT")
rows_a = list(csv.reader(l for l in open(sys.argv[3]) if not l.startswith("#")))
rows_b = list(csv.reader(l for l in open(sys.argv[4]) if not l.startswith("#")))
assert rows_a[0] == rows_b[0] and len(rows_a) == len(rows_b) and len(rows_a) > 10, (len(rows_a), len(rows_b))
for c, name in enumerate(rows_a[0]):
    check([float(r[c]) for r in rows_a[1:]], [float(r[c]) for r in rows_b[1:]], "series " + name)
print(f"{sys.argv[5]} ({form}): {n[0]} numbers; worst norm-wise relative difference {worst[0]:.1e} ({worst[1]}), "
      f"worst element-wise {worst_el[0]:.1e} ({worst_el[1]})")
PY
}
compare ref --window 0:150
compare pos --obs pos --window 0:150
compare gnss --aiding gnss
compare smooth --window 0:150 --smooth
compare expcos --window 0:150 --drift-models "$T/models.json"
echo "structured covariance = dense within 1e-9 relative"
COVS=joseph compare ref --window 0:150
COVS=joseph compare gnss --aiding gnss
echo "joseph covariance = dense within 1e-6 relative"
