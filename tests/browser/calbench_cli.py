"""The calbench runner and a free loopback port, for the console tests with and without a browser
(no Selenium needed here: the raw-HTTP tests import this alone)."""
import os
import socket
import subprocess

CB = os.environ["CALBENCH"]
SRC = os.environ["SRC"]


def run(*args, env=None, check=True):
    p = subprocess.run([CB, *args], capture_output=True, text=True, env=env)
    if check and p.returncode != 0:
        raise SystemExit(f"calbench {' '.join(args)}: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port
