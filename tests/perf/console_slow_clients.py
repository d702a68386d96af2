#!/usr/bin/python3
"""Console page latency with slow clients and open live pages (issue 54 items 10 and 12).

Starts the real `calbench serve` ($CALBENCH, else build/calbench) on a small SQLite store with one
station account, then measures, at the client, 40 requests (--requests) (GET /login and GET /queue of a session,
alternating, one at a time) in each situation:
  idle            nothing else connected
  slow N          N connections each sending one header line every 4 s (slowloris)
  live M          M open /live/events streams (M/2 sessions, two live pages each)
  slow N + live M both
and a burst: 150 (--burst) connections opened at once, each GET /login, 5 times: connections refused,
reset, or answered only after 1 s or more (a SYN dropped by a full listen queue and sent again).
Prints median, p95 and max in ms and the requests that got no answer within 10 s.

  python3 tests/perf/console_slow_clients.py [--slow 100] [--live 70] [--requests 40]
Loopback only; every loop is bounded, and the server is stopped at the end."""
import argparse
import http.client
import os
import re
import shutil
import socket
import statistics
import subprocess
import tempfile
import threading
import time
import urllib.parse

HERE = os.path.dirname(os.path.abspath(__file__))
CB = os.environ.get("CALBENCH") or os.path.join(HERE, "../../build/calbench")
PW = "pw-bench-station-1"


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    p = s.getsockname()[1]
    s.close()
    return p


def req(port, method, path, body=None, cookie=None, timeout=10):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    h = {"Cookie": cookie} if cookie else {}
    if body is not None:
        h["Content-Type"] = "application/x-www-form-urlencoded"
        body = urllib.parse.urlencode(body)
    c.request(method, path, body=body, headers=h)
    r = c.getresponse()
    out = (r.status, r.read().decode("utf-8", "replace"), r.getheader("Set-Cookie") or "")
    c.close()
    return out


def session(port):
    st, body, setc = req(port, "GET", "/login")
    pre = re.search(r"calbench_login=([0-9a-f]+)", setc).group(1)
    csrf = re.search(r'name="csrf" value="([^"]+)"', body).group(1)
    st, body, setc = req(port, "POST", "/login", {"csrf": csrf, "login": "st1", "password": PW}, f"calbench_login={pre}")
    assert st == 303, (st, body[:200])
    return "calbench_session=" + re.search(r"calbench_session=([0-9a-f]+)", setc).group(1)


REQUESTS = 40


def measure(port, cookie):
    times, missed = [], 0
    for i in range(REQUESTS):
        t0 = time.perf_counter()
        try:
            st = req(port, "GET", "/login" if i % 2 == 0 else "/queue", cookie=None if i % 2 == 0 else cookie)[0]
            if st != 200:
                missed += 1
                continue
            times.append((time.perf_counter() - t0) * 1000)
        except OSError:
            missed += 1
    return times, missed


class Slow:
    def __init__(self, port, n):
        self.socks = []
        for _ in range(n):
            try:
                s = socket.create_connection(("127.0.0.1", port), timeout=5)
                s.sendall(b"GET /login HTTP/1.1\r\nHost: x\r\n")
                self.socks.append(s)
            except OSError:
                pass
        self.stop = threading.Event()
        self.t = threading.Thread(target=self.drip)
        self.t.start()

    def drip(self):
        i = 0
        while not self.stop.is_set():
            for s in self.socks:
                try:
                    s.sendall(f"X-Slow-{i}: y\r\n".encode())
                except OSError:
                    pass
            i += 1
            self.stop.wait(4)

    def close(self):
        self.stop.set()
        self.t.join()
        for s in self.socks:
            s.close()


def open_streams(port, m):
    streams = []
    for _ in range(m // 2):
        try:
            c = session(port)
        except OSError:  # the server stopped answering (its workers are all held): fewer streams
            break
        for _ in range(2):
            try:
                s = socket.create_connection(("127.0.0.1", port), timeout=10)
                s.sendall(f"GET /live/events HTTP/1.1\r\nHost: x\r\nCookie: {c}\r\n\r\n".encode())
                streams.append(s)
            except OSError:
                pass
    time.sleep(1)
    return streams


def burst(port, n=150):
    """Connections refused or reset, plus those answered only after 1 s or more (a SYN the full
    listen queue dropped, sent again by the client's kernel), each counted as a failure."""
    errors, go = [], threading.Barrier(n)

    def one():
        go.wait()
        t0 = time.perf_counter()
        try:
            req(port, "GET", "/login", timeout=30)
            if time.perf_counter() - t0 >= 1.0:
                errors.append("answered after a dropped SYN")
        except OSError as e:
            errors.append(repr(e))

    ts = [threading.Thread(target=one) for _ in range(n)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    return len(errors)


def row(name, times, missed):
    if not times:
        print(f"{name:<24} {'-':>8} {'-':>8} {'-':>8} {missed:>7}")
        return
    p95 = sorted(times)[max(0, int(round(0.95 * len(times))) - 1)]
    print(f"{name:<24} {statistics.median(times):8.1f} {p95:8.1f} {max(times):8.1f} {missed:>7}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--slow", type=int, default=100)
    ap.add_argument("--live", type=int, default=70)
    ap.add_argument("--requests", type=int, default=40, help="requests measured per case")
    ap.add_argument("--burst", type=int, default=150, help="connections opened at once in the burst")
    ap.add_argument("--only-burst", action="store_true")
    a = ap.parse_args()
    global REQUESTS
    REQUESTS = a.requests
    work = tempfile.mkdtemp(prefix="calbench-slow-bench-")
    servers = []
    try:
        db = os.path.join(work, "s.db")
        subprocess.run([CB, "db", "init", "--db", db], check=True, capture_output=True)
        subprocess.run([CB, "db", "user", "add", "st1", "--db", db, "--name", "Sam Station", "--role", "station", "--operator", "admin"],
                       check=True, capture_output=True, env={**os.environ, "CALBENCH_PASSWORD": PW})
        servers = []

        def start():  # each case on a server of its own: what one case leaves behind does not count in the next
            port = free_port()
            servers.append(subprocess.Popen([CB, "serve", "--db", db, "--listen", f"127.0.0.1:{port}"], stdout=subprocess.DEVNULL,
                                            stderr=subprocess.DEVNULL))
            for _ in range(100):
                try:
                    req(port, "GET", "/login")
                    break
                except OSError:
                    time.sleep(0.1)
            return port, session(port)

        print(f"calbench: {CB}\n{'case':<24} {'p50 ms':>8} {'p95 ms':>8} {'max ms':>8} {'no answer':>7}")
        if a.only_burst:
            port, cookie = start()
            errs = [burst(port, a.burst) for _ in range(5)]
            print(f"burst of {a.burst} connections, 5 times: {sum(errs)} of {5 * a.burst} refused, reset or delayed >= 1 s ({errs})")
            return
        port, cookie = start()
        row("idle", *measure(port, cookie))
        port, cookie = start()
        slow = Slow(port, a.slow)
        time.sleep(1)
        row(f"slow {a.slow}", *measure(port, cookie))
        slow.close()
        port, cookie = start()
        streams = open_streams(port, a.live)
        row(f"live {len(streams)}", *measure(port, cookie))
        for s in streams:
            s.close()
        port, cookie = start()
        streams = open_streams(port, a.live)
        slow = Slow(port, a.slow)
        time.sleep(1)
        row(f"slow {a.slow} + live {len(streams)}", *measure(port, cookie))
        slow.close()
        for s in streams:
            s.close()
        port, cookie = start()
        errs = [burst(port, a.burst) for _ in range(5)]
        print(f"burst of {a.burst} connections, 5 times: {sum(errs)} of {5 * a.burst} refused, reset or delayed >= 1 s ({errs})")
    finally:
        for p in servers:
            p.terminate()
            p.wait(10)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
