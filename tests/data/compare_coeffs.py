#!/usr/bin/env python3
"""Compare estimated coefficients with a truth file (both coefficients.json schema).
Usage: compare_coeffs.py EST.json TRUTH.json NSIGMA [max_M_err_ppm] [max_bias_err_rel]
Exits 1 if any estimated coefficient lies outside NSIGMA·σ of the truth, or a bound is broken;
prints one line per triad with the worst errors."""
import json, math, sys
est, truth = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
nsig = float(sys.argv[3])
max_m = float(sys.argv[4]) * 1e-6 if len(sys.argv) > 4 else math.inf
ok = True
for tri in ("gyro", "accel"):
    worst_ratio, worst_m = 0.0, 0.0
    for i in range(3):
        pairs = [(est[tri]["bias"][i], est[tri]["sigma_bias"][i], truth[tri]["bias"][i], "bias[%d]" % i, False)]
        pairs += [(est[tri]["M"][i][j], est[tri]["sigma_M"][i][j], truth[tri]["M"][i][j], "M[%d][%d]" % (i, j), True) for j in range(3)]
        for v, s, t, name, is_m in pairs:
            if s is None:
                print("%s.%s: not determined" % (tri, name)); ok = False; continue
            r = abs(v - t) / s if s > 0 else math.inf
            worst_ratio = max(worst_ratio, r)
            if is_m: worst_m = max(worst_m, abs(v - t))
            if r > nsig:
                print("%s.%s: estimate %.6g truth %.6g sigma %.3g (%.1f sigma)" % (tri, name, v, t, s, r)); ok = False
    print("%s: worst |error|/sigma %.2f, worst |M error| %.1f ppm" % (tri, worst_ratio, worst_m * 1e6))
    if worst_m > max_m:
        print("%s: M error above %.0f ppm" % (tri, max_m * 1e6)); ok = False
sys.exit(0 if ok else 1)
