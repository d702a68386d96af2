#!/usr/bin/env bash
# calbench identify: the --json contract, MODELS.json, the plot, on a generated first-order
# Gauss–Markov series (σ = 2, T = 20 s, 1 Hz, 20000 samples) and an exp-cosine one.
set -euo pipefail
: "${CALBENCH:?}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# Series generated with awk (Box–Muller normals, exact discretisation).
awk -v seed=7 'BEGIN {
  srand(seed); pi = 3.141592653589793
  s = 2.0; T = 20.0; dt = 1.0; phi = exp(-dt / T); q = s * sqrt(1 - phi * phi)
  a = 1 / 50.0; b = 2 / 50.0; c = exp(-a * dt); cr = c * cos(b * dt); ci = c * sin(b * dt)
  qc = 0.5 * sqrt(1 - c * c)
  print "# generated"; print "t_s,gm,ec"
  x = 0; zr = 0; zi = 0
  for (i = 0; i < 20000; i++) {
    u1 = rand(); if (u1 < 1e-300) u1 = 1e-300; u2 = rand(); u3 = rand(); if (u3 < 1e-300) u3 = 1e-300; u4 = rand()
    n1 = sqrt(-2 * log(u1)) * cos(2 * pi * u2); n2 = sqrt(-2 * log(u3)) * cos(2 * pi * u4)
    n3 = sqrt(-2 * log(u1)) * sin(2 * pi * u2); n4 = sqrt(-2 * log(u3)) * sin(2 * pi * u4)
    printf "%.3f,%.10g,%.10g\n", i * dt, x, zr
    x = phi * x + q * n1
    nr = cr * zr - ci * zi + qc * n2; ni = ci * zr + cr * zi + qc * n3; zr = nr; zi = ni
  }
}' > "$tmp/series.csv"

"$CALBENCH" identify --help | grep -q -- "--max-lag" || fail "help lacks --max-lag"

"$CALBENCH" identify "$tmp/series.csv" --json --out "$tmp/models.json" --plot "$tmp/fig3.png" > "$tmp/out.json"
jq -e '.columns | length == 2' "$tmp/out.json" >/dev/null || fail "two columns expected"
for key in column model sigma alpha beta T_s paper allan; do
  jq -e --arg k "$key" '.columns[0] | has($k)' "$tmp/out.json" >/dev/null || fail "missing key $key"
done
jq -e '.columns[0].column == "gm" and .columns[0].model == "exponential" and .columns[0].beta == 0' "$tmp/out.json" >/dev/null \
  || fail "gm: exponential with beta 0 expected: $(jq -c '.columns[0] | {model, beta, evidence}' "$tmp/out.json")"
jq -e '.columns[0] | (.T_s - 1/.alpha | fabs) < 1e-9 * .T_s' "$tmp/out.json" >/dev/null || fail "T_s != 1/alpha"
# Recovered within generous bounds for one realisation of 1000 T (σ 2, T 20 s).
jq -e '.columns[0] | (.sigma > 1.7 and .sigma < 2.3 and .T_s > 15 and .T_s < 25)' "$tmp/out.json" >/dev/null \
  || fail "gm estimates off: $(jq -c '.columns[0] | {sigma, T_s}' "$tmp/out.json")"
jq -e '.columns[0].paper.exponential | has("sigma") and has("alpha")' "$tmp/out.json" >/dev/null || fail "paper.exponential"
jq -e '.columns[0].paper.exp_cosine | has("beta")' "$tmp/out.json" >/dev/null || fail "paper.exp_cosine"
jq -e '.columns[0].allan.points | length > 5' "$tmp/out.json" >/dev/null || fail "allan points"
jq -e '.columns[1].column == "ec" and .columns[1].model == "exp_cosine" and .columns[1].beta > 0' "$tmp/out.json" >/dev/null \
  || fail "ec: exp_cosine expected: $(jq -c '.columns[1] | {model, beta, evidence}' "$tmp/out.json")"
jq -e '.columns[1] | (.beta > 0.03 and .beta < 0.05 and .T_s > 40 and .T_s < 60)' "$tmp/out.json" >/dev/null \
  || fail "ec estimates off: $(jq -c '.columns[1] | {beta, T_s}' "$tmp/out.json")"

# MODELS.json: shaping filters under drift_models, n_states 1 and 2, H selects the drift.
jq -e '.format == "calbench-drift-models/1"' "$tmp/models.json" >/dev/null || fail "models format"
jq -e '.drift_models.gm.n_states == 1 and (.drift_models.gm.A[0][0] < 0) and .drift_models.gm.H == [1]' "$tmp/models.json" >/dev/null || fail "gm filter"
jq -e '.drift_models.ec.n_states == 2 and .drift_models.ec.H == [0,1] and (.drift_models.ec.discrete.Phi | length == 2)' "$tmp/models.json" >/dev/null || fail "ec filter"
# Stationary variance of the output equals σ².
jq -e '.drift_models.ec | ((.P_inf[1][1] / (.sigma * .sigma)) - 1 | fabs) < 1e-9' "$tmp/models.json" >/dev/null || fail "P_inf"

# Plots are PNG files.
head -c 8 "$tmp/fig3.png" | od -An -c | grep -q "P   N   G" || fail "fig3.png is not a PNG"
head -c 8 "$tmp/fig3-allan.png" | od -An -c | grep -q "P   N   G" || fail "fig3-allan.png is not a PNG"

# --column selects, --max-lag is honoured, text output works.
"$CALBENCH" identify "$tmp/series.csv" --column gm --max-lag 40 --json > "$tmp/one.json"
jq -e '.columns | length == 1' "$tmp/one.json" >/dev/null || fail "--column"
jq -e '.columns[0].max_lag_s == 40' "$tmp/one.json" >/dev/null || fail "--max-lag"
"$CALBENCH" identify "$tmp/series.csv" --column ec --no-allan | grep -q "exp_cosine" || fail "text output"
echo OK
