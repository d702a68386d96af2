#!/usr/bin/env bash
# HDF5 recordings (docs/recording-hdf5.md): `calbench convert` CSV -> HDF5 -> CSV is bit for bit
# (the CSV files byte for byte, the datasets value for value), every command that reads a
# recording gives the same answer from either form, h5py reads the file as documented, and bad
# input (a truncated file, a dataset of the wrong type or shape, a missing column or dataset, an
# existing output) exits 2 naming the file, the dataset and the field; an interrupted conversion
# leaves no output folder.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
PY=/usr/bin/python3  # Debian's, with python3-h5py (scripts/setup)

"$CALBENCH" simulate drive --route "$SRC/bench/routes/short.toml" --truth random --seed 7 --out drive >/dev/null
"$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --seed 7 --out bench >/dev/null

# Round trips.
for r in drive bench; do
  "$CALBENCH" convert $r --to h5 --json > conv.json
  test -s $r-h5/recording.h5 && test -s $r-h5/meta.json && test -s $r-h5/truth.json || fail "$r-h5 incomplete"
  ls $r-h5/*.csv 2>/dev/null && fail "$r-h5 holds CSV files"
  "$CALBENCH" convert $r-h5 --to csv --out $r-back >/dev/null
  for f in $r/*.csv; do cmp "$f" "$r-back/$(basename "$f")" || fail "$f changed in the round trip"; done
  "$CALBENCH" convert $r-back --to h5 --out $r-h5b >/dev/null
  h5diff $r-h5/recording.h5 $r-h5b/recording.h5 || fail "$r: datasets differ after csv -> h5 -> csv -> h5"
done
"$CALBENCH" convert drive --to csv 2>err.txt && fail "converting CSV to CSV must fail"
grep -q "already CSV" err.txt || fail "$(cat err.txt)"

# h5py reads it as documented: one 2-D float64 dataset per table, names in "columns" (fixed-length
# strings), the meta.json text as a root attribute; the values equal the CSV's.
$PY - <<'PY'
import h5py, json, csv, numpy as np
f = h5py.File("drive-h5/recording.h5", "r")
txt = lambda v: v.decode() if isinstance(v, bytes) else str(v)
assert txt(f.attrs["format"]) == "calbench-recording-hdf5/1", f.attrs["format"]
assert json.loads(txt(f.attrs["meta_json"]))["kind"] == "drive"
for name in ("imu", "reference", "gnss"):
    d = f[name]
    assert d.dtype == np.float64 and d.ndim == 2 and d.chunks is not None, (name, d.dtype, d.shape, d.chunks)
    cols = [c.decode() if isinstance(c, bytes) else c for c in d.attrs["columns"]]
    rows = list(csv.reader(l for l in open(f"drive/{name}.csv") if not l.startswith("#")))
    assert cols == rows[0], (cols, rows[0])
    a = np.array([[float(v) for v in r] for r in rows[1:]])
    assert a.shape == d.shape and (a == d[...]).all(), name
print("h5py: datasets equal the CSV files")
PY

# Every reading command: the same answer from either form.
# Lines that name the folder (path, URI) or its digests, and timings.
IGNORE='"path"\|"uri"\|sha256\|"format": "hdf5"\|cpu_s\|wall_s\|"dir"\|"input": "drive'
same() {  # what, then the command with @ for the recording folder
  local what=$1
  shift
  "${@//@/drive}" > a.out
  "${@//@/drive-h5}" > b.out
  diff <(grep -v "$IGNORE" a.out) <(grep -v "$IGNORE" b.out) >/dev/null || { diff a.out b.out | head; fail "$what differs"; }
}
same "fit drive" "$CALBENCH" fit drive @ --window 0:150 --json --out r.json
"$CALBENCH" fit drive drive --window 0:150 --out r.json >/dev/null
same "qc" "$CALBENCH" qc @ --coeffs r.json --coeffs none --json
same "diagnose" "$CALBENCH" diagnose @ --json
same "identify" "$CALBENCH" identify @ --column gz_rad_s --json
jq -e '.recording.format == "hdf5"' <("$CALBENCH" fit drive drive-h5 --window 0:150 --json --out r2.json) >/dev/null || fail "RESULT.json must say the recording is HDF5"
"$CALBENCH" fit bench bench --json --out c1.json > b1.json
"$CALBENCH" fit bench bench-h5 --json --out c2.json > b2.json
# (created_utc: when each set was made, a second apart when the clock ticks between the two fits)
diff <(grep -v '"recording"\|"created_utc"' c1.json) <(grep -v '"recording"\|"created_utc"' c2.json) || fail "fit bench differs between CSV and HDF5"

# Bad input: exit 2, the file, the dataset, the field.
expect2() {  # pattern, then the command
  local pat=$1
  shift
  set +e
  "$@" > out.txt 2> err.txt
  local rc=$?
  set -e
  [ $rc -eq 2 ] || fail "exit $rc (expected 2) for $*: $(cat err.txt)"
  grep -Eq -- "$pat" err.txt || fail "message for $* does not match '$pat': $(cat err.txt)"
}
mkdir bad1 && cp drive-h5/meta.json bad1/ && head -c 300000 drive-h5/recording.h5 > bad1/recording.h5
expect2 "bad1/recording\.h5: .*(truncated|damaged|cut short)" "$CALBENCH" fit drive bad1 --out x.json
$PY - <<'PY'
import h5py, numpy as np, shutil, os
def variant(dirname, edit):
    os.makedirs(dirname)
    shutil.copy("drive-h5/meta.json", dirname)
    shutil.copy("drive-h5/recording.h5", dirname)
    with h5py.File(f"{dirname}/recording.h5", "r+") as f:
        edit(f)
def retype(f):  # imu as 32-bit integers
    d = f["imu"][...]; cols = f["imu"].attrs["columns"]
    del f["imu"]; n = f.create_dataset("imu", data=d.astype(np.int32)); n.attrs["columns"] = cols
def reshape(f):  # imu as a 1-D array
    d = f["imu"][...]; cols = f["imu"].attrs["columns"]
    del f["imu"]; n = f.create_dataset("imu", data=d.ravel()); n.attrs["columns"] = cols
def names(f):
    return [c.decode() if isinstance(c, bytes) else c for c in f["imu"].attrs["columns"]]
def rename(f):   # a required column renamed away (fixed-length strings, as the format has them)
    f["imu"].attrs["columns"] = np.array([c.replace("gz_rad_s", "gz") for c in names(f)], dtype="S")
def shorten(f):  # fewer names than columns
    f["imu"].attrs["columns"] = np.array(names(f)[:-1], dtype="S")
def vlen(f):     # the names as variable-length strings (h5py's default for a list of str)
    f["imu"].attrs["columns"] = names(f)
def nan(f):
    d = f["reference"]; d[5, 1] = np.nan
def drop(f):
    del f["reference"]
variant("bad2", retype); variant("bad3", reshape); variant("bad4", rename); variant("bad5", shorten)
variant("bad6", nan); variant("bad7", drop); variant("bad8", vlen)
PY
expect2 "bad2/recording\.h5: '/imu': dataset /imu has the wrong type" "$CALBENCH" fit drive bad2 --out x.json
expect2 "bad3/recording\.h5: '/imu': dataset /imu has the wrong shape: expected 2 dimensions" "$CALBENCH" fit drive bad3 --out x.json
expect2 "bad4/recording\.h5: 'gz_rad_s': dataset /imu: missing required column" "$CALBENCH" fit drive bad4 --out x.json
expect2 "bad5/recording\.h5: '/imu': dataset /imu has the wrong shape: [0-9]+ columns but [0-9]+ names" "$CALBENCH" fit drive bad5 --out x.json
expect2 "bad6/recording\.h5: 'lat_deg': dataset /reference, row 6: NaN or infinity" "$CALBENCH" fit drive bad6 --out x.json
expect2 "bad7/recording\.h5: .*(reference|gnss)" "$CALBENCH" fit drive bad7 --aiding reference --out x.json
expect2 "bad8/recording\.h5: '/imu': dataset /imu attribute 'columns': variable-length strings are not read" "$CALBENCH" fit drive bad8 --out x.json
expect2 "bad2/recording\.h5: '/imu': dataset /imu has the wrong type" "$CALBENCH" convert bad2 --to csv
test ! -e bad2-csv || fail "a failed conversion left bad2-csv"
ls -a | grep -q "partial" && fail "a failed conversion left a partial folder"
expect2 "--out: .*exists" "$CALBENCH" convert drive --to h5 --out drive-h5
expect2 "--to: " "$CALBENCH" convert drive --to hdf5

# A source that cannot be read fully is refused, nothing written (issue 35): a recording.h5 cut
# in half or of 0 bytes once converted to a folder of meta.json alone, marked complete.
mkdir half zero
cp drive-h5/meta.json drive-h5/truth.json half/ && cp drive-h5/meta.json zero/
head -c $(( $(stat -c %s drive-h5/recording.h5) / 2 )) drive-h5/recording.h5 > half/recording.h5
: > zero/recording.h5
expect2 "^calbench: error: half/recording\.h5: .*(truncated|damaged|cut short)" "$CALBENCH" convert half --to csv --out half-csv
expect2 "^calbench: error: zero/recording\.h5: not an HDF5 file" "$CALBENCH" convert zero --to csv --out zero-csv
test ! -e half-csv && test ! -e zero-csv || fail "a refused conversion left its output"
ls -a | grep -q "partial" && fail "a refused conversion left a partial folder"

# Time order is checked converting either way (issue 35), as every reader checks it.
$PY - <<'PY'
import h5py, shutil, os
for name, row, how in (("imu", 40, "back"), ("reference", 7, "dup"), ("gnss", 3, "back")):
    d = f"order-{name}"
    os.makedirs(d); shutil.copy("drive-h5/meta.json", d); shutil.copy("drive-h5/recording.h5", d)
    with h5py.File(f"{d}/recording.h5", "r+") as f:
        t = f[name][row - 2, 0]
        f[name][row - 1, 0] = t if how == "dup" else t - 1.0
PY
expect2 "order-imu/recording\.h5: 't_s': dataset /imu, row 40: time goes backwards" "$CALBENCH" convert order-imu --to csv --out o1
expect2 "order-reference/recording\.h5: 't_s': dataset /reference, row 7: duplicated time" "$CALBENCH" convert order-reference --to csv --out o2
expect2 "order-gnss/recording\.h5: 't_s': dataset /gnss, row 3: time goes backwards" "$CALBENCH" convert order-gnss --to csv --out o3
test ! -e o1 && test ! -e o2 && test ! -e o3 || fail "a conversion refused for its time order left its output"

# One row per chunk (h5py chunks=(1, n)): read in one chunk-index walk, not one per chunk (issue
# 35: 75,807 rows took 79 s in fit bench; 40,000 rows of imu and reference 36.7 s in convert). The
# values read through the block path equal the CSV's.
$PY - <<'PY'
import h5py, numpy as np, csv, os, shutil
os.makedirs("chunks1"); shutil.copy("bench/meta.json", "chunks1")
with h5py.File("chunks1/recording.h5", "w") as f:
    for name in ("imu", "reference"):
        rows = list(csv.reader(l for l in open(f"bench/{name}.csv") if not l.startswith("#")))
        a = np.array([[float(v) for v in r] for r in rows[1:30001]])
        d = f.create_dataset(name, data=a, chunks=(1, a.shape[1]), maxshape=(None, a.shape[1]))
        d.attrs["columns"] = np.array(rows[0], dtype="S")
PY
# (its speed is measured in the benchmark BM_Read_Imu_OneRowChunks, tests/perf, not timed here)
"$CALBENCH" convert chunks1 --to csv --out chunks1-csv > /dev/null
for t in imu reference; do
  diff <(grep -v '^#' bench/$t.csv | head -n 30001) <(grep -v '^#' chunks1-csv/$t.csv) > /dev/null || fail "1-row chunks: $t values differ"
done

# Many small chunks, one never written (h5py leaves it unallocated): refused, not read as zeros.
$PY - <<'PY'
import h5py, numpy as np, shutil, os
os.makedirs("sparse"); shutil.copy("drive-h5/meta.json", "sparse")
with h5py.File("sparse/recording.h5", "w") as f:
    a = np.zeros((1100, 7)); a[:, 0] = np.arange(1100) * 0.01; a[:, 6] = -9.8
    d = f.create_dataset("imu", shape=a.shape, chunks=(1, 7), dtype="f8")
    d[:1000] = a[:1000]; d[1001:] = a[1001:]
    d.attrs["columns"] = np.array(["t_s", "gx_rad_s", "gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2"], dtype="S")
PY
expect2 "sparse/recording\.h5: '/imu': dataset /imu, rows from 1: their values are not all stored \(1099 of 1100 chunks" "$CALBENCH" convert sparse --to csv --out sparse-csv
test ! -e sparse-csv || fail "a refused conversion left sparse-csv"

# Interrupted: SIGTERM while converting leaves neither the output nor a partial folder.
"$CALBENCH" simulate drive --route "$SRC/bench/routes/gnss_1h.toml" --truth random --seed 8 --until 2400 --out long >/dev/null
"$CALBENCH" convert long --to h5 --out long-h5 & pid=$!
sleep 0.1
kill -TERM $pid 2>/dev/null || true
if wait $pid; then echo "(conversion finished before the signal)"; else test ! -e long-h5 || fail "interrupted, yet long-h5 exists"; fi
if [ -e long-h5 ]; then h5diff long-h5/recording.h5 long-h5/recording.h5 >/dev/null || fail "long-h5 exists but is not complete"; fi
ls -a | grep -q "partial" && fail "an interrupted conversion left a partial folder"
echo "HDF5 recordings: round trips bit for bit, every reader agrees, bad input exits 2"
