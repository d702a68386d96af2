#!/usr/bin/env python3
"""The body of docs/validation/perf-inmotion.md from a Google Benchmark JSON of
tests/perf/recording_io_bench.cpp (BM_Read_*, BM_FitDrive/*, BM_FitDrive_Baseline/*): medians.
Usage: inmotion_perf_table.py RESULTS.json BASELINE_NAME > body.md"""
import json, re, sys

runs = json.load(open(sys.argv[1]))["benchmarks"]
base = sys.argv[2] if len(sys.argv) > 2 else "baseline"
med = {}
for r in runs:
    if r.get("aggregate_name") == "median":
        med[r["run_name"]] = r

def secs(r):
    return r["real_time"] * {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[r["time_unit"]]

print("| read | rows | median | rows/s | MB/s |")
print("|---|---|---|---|---|")
for name, r in med.items():
    m = re.match(r"BM_Read_(Imu|Reference)/(?:rate:(\d+)/)?h5:(\d)", name)
    if not m:
        continue
    what = ("IMU %s Hz" % m.group(2) if m.group(1) == "Imu" else "reference 100 Hz") + (", HDF5" if m.group(3) == "1" else ", CSV")
    rows = r.get("rows", 360001 if m.group(1) == "Reference" else 0)
    print("| %s | %s | %.1f ms | %.1f M | %.0f |" % (what, "{:,}".format(int(rows)) if rows else "360,001", secs(r) * 1e3,
                                                 r["rows_per_s"] / 1e6, r["MB_per_s"]))
print()
print("| fit drive, 1 h | %s (CSV) | CSV | HDF5 | speed-up CSV / HDF5 | ns per IMU epoch (CSV / HDF5) | peak RSS (%s / CSV / HDF5) |" % (base, base))
print("|---|---|---|---|---|---|---|")
for rate in (200, 2460):
    for att, obs in ((0, "pos"), (1, "pos,vel,att")):
        b = med.get("BM_FitDrive_Baseline/rate:%d/att:%d/iterations:1/repeats:5/manual_time" % (rate, att))
        c = med.get("BM_FitDrive/rate:%d/att:%d/h5:0/iterations:1/repeats:5/manual_time" % (rate, att))
        h = med.get("BM_FitDrive/rate:%d/att:%d/h5:1/iterations:1/repeats:5/manual_time" % (rate, att))
        if not (c and h):
            continue
        bs = "%.2f s" % secs(b) if b else "–"
        sp = "%.2f× / %.2f×" % (secs(b) / secs(c), secs(b) / secs(h)) if b else "–"
        rss = "%s / %.0f / %.0f MB" % ("%.0f" % b["peak_rss_MB"] if b else "–", c["peak_rss_MB"], h["peak_rss_MB"])
        print("| %d Hz, `--obs %s` | %s | %.2f s | %.2f s | %s | %.0f / %.0f | %s |" % (
            rate, obs, bs, secs(c), secs(h), sp, c["ns_per_imu_epoch"], h["ns_per_imu_epoch"], rss))
