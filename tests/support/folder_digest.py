#!/usr/bin/env python3
"""folder_digest.py FOLDER: the recording digest of docs/database.md, computed independently of
calbench (bench/io/recording_location.cpp): SHA-256 over every regular file under FOLDER, in the
byte order of their '/'-separated relative paths, each as PATH NUL SIZE NUL BYTES."""
import hashlib
import os
import sys

root = sys.argv[1]
files = []
for d, _, names in os.walk(root):
    for n in names:
        p = os.path.join(d, n)
        if os.path.isfile(p):
            files.append(os.path.relpath(p, root).replace(os.sep, "/"))
files.sort(key=lambda s: s.encode())
h = hashlib.sha256()
for f in files:
    p = os.path.join(root, f)
    h.update(f.encode() + b"\0" + str(os.path.getsize(p)).encode() + b"\0")
    with open(p, "rb") as fh:
        h.update(fh.read())
print(h.hexdigest())
