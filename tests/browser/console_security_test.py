#!/usr/bin/python3
"""The console's security limits (issue 54 items 7-10, 12) on a SQLite store, by raw HTTP beside
what a browser does: parallel password guesses, guessing across logins from one address, the login
form's token, a session whose account changed, the security audit and the server's log, slow clients,
many open live pages, the listen backlog, HSTS and the Secure cookie under TLS.

Each case measures the behaviour (counts of 401 against 429, whether a page is answered while slow
clients and live streams are open) with bounds generous for a loaded 2-core machine; speed itself is
measured by tests/perf/console_slow_clients.py. Run by ctest (browser.console_security) with CALBENCH
and SRC set."""
import http.client
import json
import os
import re
import shutil
import socket
import sqlite3
import ssl
import subprocess
import sys
import tempfile
import threading
import time

from calbench_cli import CB, SRC, free_port, run  # noqa: E402
PW = {"qc1": "pw-quinn-1234", "qc2": "pw-rita-12345", "st1": "pw-sam-123456"}


class Server:
    """`calbench serve` on a free port, its log kept; stopped by stop()."""

    def __init__(self, work, db, *extra, tls=None):
        self.port = free_port()
        self.log_path = os.path.join(work, f"serve-{self.port}.log")
        self.log = open(self.log_path, "w")
        args = [CB, "serve", "--db", db, "--listen", f"127.0.0.1:{self.port}", *extra]
        if tls:
            args += ["--tls-cert", tls[0], "--tls-key", tls[1]]
        self.tls = tls
        self.proc = subprocess.Popen(args, stdout=self.log, stderr=self.log)
        for _ in range(100):
            try:
                self.req("GET", "/login")
                return
            except OSError:
                if self.proc.poll() is not None:
                    raise SystemExit(f"calbench serve {' '.join(extra)} ended: " + open(self.log_path).read())
                time.sleep(0.1)

    def conn(self, timeout=30):
        if self.tls:
            ctx = ssl.create_default_context()
            ctx.check_hostname = False
            ctx.verify_mode = ssl.CERT_NONE
            return http.client.HTTPSConnection("127.0.0.1", self.port, timeout=timeout, context=ctx)
        return http.client.HTTPConnection("127.0.0.1", self.port, timeout=timeout)

    def req(self, method, path, body=None, cookie=None, timeout=30, headers=False):
        import urllib.parse
        c = self.conn(timeout)
        h = {"Cookie": cookie} if cookie else {}
        if body is not None:
            h["Content-Type"] = "application/x-www-form-urlencoded"
            body = urllib.parse.urlencode(body)
        c.request(method, path, body=body, headers=h)
        r = c.getresponse()
        out = (r.status, r.read().decode("utf-8", "replace"), r.getheader("Set-Cookie") or "")
        hd = dict(r.getheaders())
        c.close()
        return out + (hd,) if headers else out

    def form(self):
        """A login form: its cookie and its token."""
        st, body, setc = self.req("GET", "/login")
        assert st == 200, st
        return re.search(r"calbench_login=([0-9a-f]+)", setc).group(1), re.search(r'name="csrf" value="([^"]+)"', body).group(1)

    def login(self, user, pw, form=None):
        pre, csrf = form or self.form()
        return self.req("POST", "/login", {"csrf": csrf, "login": user, "password": pw}, f"calbench_login={pre}")

    def session(self, user):
        st, body, setc = self.login(user, PW[user])
        assert st == 303, (user, st, body[:300])
        return "calbench_session=" + re.search(r"calbench_session=([0-9a-f]+)", setc).group(1)

    def csrf(self, cookie, page="/set/1"):
        st, body, _ = self.req("GET", page, cookie=cookie)
        assert st == 200, (st, body[:300])
        return re.search(r'name="csrf" value="([0-9a-f]+)"', body).group(1)

    def logged(self):
        self.log.flush()
        return open(self.log_path).read()

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            self.proc.wait(10)


def security_rows(db):
    con = sqlite3.connect(db)
    rows = con.execute("SELECT action, detail FROM audit_log WHERE entity = 'security' ORDER BY id").fetchall()
    con.close()
    return rows


def set_status(db):
    return json.loads(run("db", "show", "SIMS1", "--db", db, "--json").stdout)["sets"][0]["status"]


def parallel_guesses(srv, db):
    """Item 7: 40 simultaneous POST /login for qc1, the right password at position 30. Each attempt
    is reserved before its check: at most 5 passwords are checked, the rest are refused (429)."""
    forms = [srv.form() for _ in range(40)]
    go = threading.Barrier(40)
    out = [None] * 40

    def attempt(i):
        pw = PW["qc1"] if i == 30 else f"wrong-guess-{i:02d}"
        go.wait()
        out[i] = srv.login("qc1", pw, forms[i])[0]

    threads = [threading.Thread(target=attempt, args=(i,)) for i in range(40)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    checked = sum(1 for s in out if s in (401, 303))
    print(f"40 parallel guesses: {out.count(401)} answered 401, {out.count(303)} 303, {out.count(429)} 429")
    assert checked <= 5 and out.count(401) + out.count(303) + out.count(429) == 40, out
    # Then wrong passwords one by one until the login locks: never more than 5 failures in all.
    after = 0
    while True:
        st = srv.login("qc1", "wrong-again-x")[0]
        if st != 401:
            break
        after += 1
        assert after <= 5, "more than 5 failures without a lock-out"
    assert st == 429, st
    failures = out.count(401) + after
    assert failures <= 5 + (5 if 303 in out else 0), (out, after)
    st, body, _ = srv.login("qc1", PW["qc1"])
    assert st == 429 and "locked" in body, (st, body[:300])
    rows = security_rows(db)
    fails = [d for a, d in rows if a == "login-failed" and d.startswith("qc1")]
    locks = [d for a, d in rows if a == "lockout" and d.startswith("qc1")]
    assert len(fails) == failures and len(locks) == 1, rows
    assert all("127.0.0.1" in d for d in fails) and not any("wrong" in d for a, d in rows), rows


def login_token(srv):
    """Item 9: the login form's token is bound to its cookie (an HMAC with the server's key): a
    double-submit pair made up by another site, or a token from another form, is refused (403)."""
    forged = "ab" * 32
    st, body, _ = srv.req("POST", "/login", {"csrf": forged, "login": "qc2", "password": PW["qc2"]}, f"calbench_login={forged}")
    assert st == 403 and "token" in body, (st, body[:300])
    (pre1, _), (_, tok2) = srv.form(), srv.form()
    st, body, _ = srv.req("POST", "/login", {"csrf": tok2, "login": "qc2", "password": PW["qc2"]}, f"calbench_login={pre1}")
    assert st == 403, (st, body[:300])


def role_change(srv, db, work):
    """Item 8: qc2 has two sessions; its account becomes a station account with a new password: both
    sessions end at their next request, nothing is approved. A station's refused approval is audited."""
    a, b = srv.session("qc2"), srv.session("qc2")
    csrf = srv.csrf(a)
    st1 = srv.session("st1")
    st, body, _ = srv.req("POST", "/set/1/approve", {"csrf": srv.csrf(st1)}, st1)
    assert st == 403 and set_status(db) == "draft", (st, body[:300])
    # The account made a station account with another password (st1's) by an admin, appointed first
    # with a qc account's password (docs/database.md "Threat model").
    run("db", "user", "add", "boss", "--db", db, "--name", "Ada Admin", "--role", "admin", "--admin", "qc1",
        env={**os.environ, "CALBENCH_PASSWORD": "boss-pass-1", "CALBENCH_ADMIN_PASSWORD": PW["qc1"]})
    run("db", "user", "add", "qc2", "--db", db, "--name", "Rita Review", "--role", "station", "--admin", "boss",
        env={**os.environ, "CALBENCH_PASSWORD": PW["st1"], "CALBENCH_ADMIN_PASSWORD": "boss-pass-1"})
    st, body, _ = srv.req("POST", "/set/1/approve", {"csrf": csrf}, a)
    assert st == 401 and "session has ended" in body and "role" in body, (st, body[:400])
    assert set_status(db) == "draft"
    st, body, _ = srv.req("GET", "/queue", cookie=b)
    assert st in (303, 401), (st, body[:300])
    rows = security_rows(db)
    assert any(a_ == "refused" and d.startswith("st1") and "approve" in d for a_, d in rows), rows
    assert any(a_ == "refused" and d.startswith("qc2") and "session ended" in d for a_, d in rows), rows
    log = srv.logged()
    assert re.search(r"calbench serve: 127\.0\.0\.1 qc2 POST /set/1/approve 401", log), log[-1500:]
    assert re.search(r"calbench serve: 127\.0\.0\.1 qc1 POST /login 429", log), log[-1500:]
    for secret in (*PW.values(), "wrong-guess-03"):
        assert secret not in log, "a password reached the log"


def slow_clients(srv, n=100):
    """Item 10: n connections that send one header line every 4 s. GET /login is still answered
    within 5 s, and the server drops the slow ones after its request deadline (10 s)."""
    socks = []
    for _ in range(n):
        s = socket.create_connection(("127.0.0.1", srv.port), timeout=5)
        s.sendall(b"GET /login HTTP/1.1\r\nHost: x\r\n")
        socks.append(s)
    stop = threading.Event()
    closed = set()

    def drip():
        i = 0
        while not stop.is_set():
            for k, s in enumerate(socks):
                if k in closed:
                    continue
                try:
                    s.sendall(f"X-Slow-{i}: {'y' * 20}\r\n".encode())
                except OSError:
                    closed.add(k)
            i += 1
            stop.wait(4)

    t = threading.Thread(target=drip)
    t.start()
    try:
        time.sleep(1)
        t0 = time.time()
        st, _, _ = srv.req("GET", "/login", timeout=5)
        took = time.time() - t0
        assert st == 200, st
        print(f"GET /login with {n} slow clients: {took:.3f} s")
        # Every slow connection is closed by the server within its deadline (10 s) and some slack.
        deadline = time.time() + 25
        while time.time() < deadline and len(closed) < n:
            for k, s in enumerate(socks):
                if k in closed:
                    continue
                s.setblocking(False)
                try:
                    if s.recv(4096) == b"":
                        closed.add(k)
                except BlockingIOError:
                    pass
                except OSError:
                    closed.add(k)
            time.sleep(0.5)
        assert len(closed) == n, f"{n - len(closed)} slow clients still connected after 25 s"
    finally:
        stop.set()
        t.join()
        for s in socks:
            s.close()


def header_flood(srv):
    """Item 10: a request with 200 KiB of header lines (each line short) is refused (400) or cut off,
    not read to its end and served: a request is at most 96 KiB."""
    s = socket.create_connection(("127.0.0.1", srv.port), timeout=15)
    try:
        s.sendall(b"GET /login HTTP/1.1\r\nHost: x\r\n")
        sent = 0
        try:
            while sent < 200 * 1024:
                s.sendall(f"X-Flood-{sent}: {'z' * 100}\r\n".encode())
                sent += 120
            s.sendall(b"\r\n")
        except OSError:
            pass  # the server closed the connection while we were still sending: cut off
        try:
            answer = s.recv(4096).decode("latin-1")
        except OSError:
            answer = ""
        assert not answer.startswith("HTTP/1.1 200"), answer[:200]
        print(f"200 KiB of headers: {answer.splitlines()[0] if answer else 'connection closed'}")
    finally:
        s.close()


def open_stream(srv, cookie):
    s = socket.create_connection(("127.0.0.1", srv.port), timeout=30)
    s.sendall(f"GET /live/events HTTP/1.1\r\nHost: x\r\nCookie: {cookie}\r\n\r\n".encode())
    head = b""
    while b"\r\n\r\n" not in head:
        chunk = s.recv(4096)
        if not chunk:
            break
        head += chunk
    return s, head.decode("latin-1")


def read_until(s, needle, timeout=10, first=""):
    s.settimeout(timeout)
    got = first.encode("latin-1")
    deadline = time.time() + timeout
    while needle.encode() not in got and time.time() < deadline:
        try:
            chunk = s.recv(65536)
        except socket.timeout:
            break
        if not chunk:
            break
        got += chunk
    return needle.encode() in got


def live_streams(srv):
    """Item 10: 35 sessions with two live pages each (70 streams, more than the old 64 workers):
    pages are still answered; a session's third stream replaces its first ('replaced')."""
    cookies = [srv.session("st1") for _ in range(35)]
    streams, heads = [], []
    try:
        for c in cookies:
            for _ in range(2):
                s, head = open_stream(srv, c)
                assert head.startswith("HTTP/1.1 200"), head[:200]
                streams.append(s)
                heads.append(head)
        assert all(read_until(s, "event: live", 20, first) for s, first in zip(streams[:3], heads[:3]))
        t0 = time.time()
        st, _, _ = srv.req("GET", "/login", timeout=5)
        st2, body, _ = srv.req("GET", "/queue", cookie=cookies[0], timeout=5)
        took = time.time() - t0
        assert st == 200 and st2 == 200 and "queue" in body, (st, st2)
        print(f"GET /login + /queue with {len(streams)} live streams open: {took:.3f} s")
        third, head = open_stream(srv, cookies[0])
        streams.append(third)
        assert head.startswith("HTTP/1.1 200"), head[:200]
        assert read_until(streams[0], "event: replaced", 10, heads[0]), "the session's oldest stream was not replaced"
    finally:
        for s in streams:
            s.close()


def stream_cap(work, db):
    """Item 10: --live-streams 4: a fifth stream (another session) gets 503 with an SSE retry."""
    srv = Server(work, db, "--live-streams", "4")
    streams = []
    try:
        a, b, c = srv.session("qc1"), srv.session("st1"), srv.session("qc2")
        for ck in (a, a, b, b):
            s, head = open_stream(srv, ck)
            assert head.startswith("HTTP/1.1 200"), head[:200]
            streams.append(s)
        s, head = open_stream(srv, c)
        streams.append(s)
        assert head.startswith("HTTP/1.1 503") and "Retry-After" in head, head[:300]
        assert read_until(s, "retry: ", 5, head), head
    finally:
        for s in streams:
            s.close()
        srv.stop()


def backlog_and_burst(srv):
    """Item 12: the listen backlog (ss's Send-Q of a listening socket) and a burst of 150
    connections at once, every one answered."""
    ss = subprocess.run(["ss", "-ltnH", f"sport = :{srv.port}"], capture_output=True, text=True).stdout.split()
    somaxconn = int(open("/proc/sys/net/core/somaxconn").read())
    assert ss and int(ss[2]) >= min(1024, somaxconn), ss
    errors, statuses = [], []
    go = threading.Barrier(150)

    def one():
        go.wait()
        try:
            statuses.append(srv.req("GET", "/login", timeout=30)[0])
        except OSError as e:
            errors.append(repr(e))

    threads = [threading.Thread(target=one) for _ in range(150)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    print(f"backlog {ss[2]}; burst of 150: {statuses.count(200)} answered, {len(errors)} errors")
    assert not errors and statuses.count(200) == 150, (errors[:3], statuses)


def connection_cap(work, db):
    """Item 10: --max-connections 8 (at most 4 from one address): of five connections opened from
    this address, one is answered 503 at once while four wait for their request; once they are
    closed, pages are served again."""
    srv = Server(work, db, "--max-connections", "8")
    conns = []
    try:
        for _ in range(5):
            conns.append(socket.create_connection(("127.0.0.1", srv.port)))
            time.sleep(0.2)
        answered = {}
        deadline = time.time() + 5
        while time.time() < deadline and not answered:
            for k, c in enumerate(conns):
                c.setblocking(False)
                try:
                    got = c.recv(4096)
                    answered[k] = got.decode("latin-1")
                except BlockingIOError:
                    pass
            time.sleep(0.2)
        time.sleep(0.5)  # no second refusal follows
        for k, c in enumerate(conns):
            try:
                answered.setdefault(k, c.recv(4096).decode("latin-1"))
            except BlockingIOError:
                pass
        assert len(answered) == 1, answered
        busy = next(iter(answered.values()))
        assert busy.startswith("HTTP/1.1 503") and "too many connections" in busy, busy[:200]
        for c in conns:
            c.close()
        conns = []
        deadline = time.time() + 5
        while srv.req("GET", "/login", timeout=5)[0] != 200:
            assert time.time() < deadline, "still refused after the connections closed"
            time.sleep(0.2)
    finally:
        for c in conns:
            c.close()
        srv.stop()


def address_limit(work, db):
    """Item 7: guesses across many logins from one address: after 30 failures within 15 min the
    address is refused (429), without a lock on any login."""
    srv = Server(work, db)
    try:
        out = [srv.login(f"nobody{i}", "not-a-password")[0] for i in range(32)]
        assert out[:30] == [401] * 30 and out[30:] == [429, 429], out
        st, body, _ = srv.login("qc1", PW["qc1"])
        assert st == 429 and "address" in body, (st, body[:300])
    finally:
        srv.stop()


def tls(work, db):
    """Item 9: under TLS the answers carry Strict-Transport-Security and the session cookie Secure;
    a client that opens a connection and never says anything does not hold up the page."""
    cert, key = os.path.join(work, "c.pem"), os.path.join(work, "k.pem")
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-subj", "/CN=localhost", "-days", "2",
                    "-keyout", key, "-out", cert], check=True, capture_output=True)
    srv = Server(work, db, tls=(cert, key))
    try:
        idle = [socket.create_connection(("127.0.0.1", srv.port)) for _ in range(20)]
        st, _, _, h = srv.req("GET", "/login", timeout=5, headers=True)
        assert st == 200 and h.get("Strict-Transport-Security", "").startswith("max-age="), h
        st, _, setc = srv.login("qc1", PW["qc1"])
        assert st == 303 and "Secure" in setc, (st, setc)
        for s in idle:
            s.close()
    finally:
        srv.stop()


def main():
    if not shutil.which("ss") or not shutil.which("openssl"):
        print("ss or openssl missing: skipped")
        sys.exit(77)
    work = tempfile.mkdtemp(prefix="calbench-console-sec-")
    servers = []
    try:
        db = os.path.join(work, "store.db")
        sim = os.path.join(work, "sim")
        subprocess.run([sys.executable, os.path.join(SRC, "bench/multipos/sim_effects.py"), sim, "--seed", "503", "--poses", "24"],
                       check=True, capture_output=True)
        rec = os.path.join(work, "rec")
        run("import", "imu-tk", f"{sim}/acc.txt", f"{sim}/gyro.txt", "--out", rec, "--model", "ADIS16488A", "--serial", "SIMS1",
            "--site-lat", "52")
        coeffs = os.path.join(work, "c.json")
        fit = json.loads(run("fit", "multipos", rec, "--out", coeffs, "--json").stdout)["multipos"]
        run("db", "store-bench", "--db", db, "--coeffs", coeffs, "--recording", rec, "--operator", "qc1", "--qc",
            f"g_loo_rms={fit['g_loo_rms_m_s2']}:{fit['qc_g_loo_limit_m_s2']}:m/s2:out-of-sample")
        for login, name, role in (("qc1", "Quinn QA", "qc"), ("qc2", "Rita Review", "qc"), ("st1", "Sam Station", "station")):
            run("db", "user", "add", login, "--db", db, "--name", name, "--role", role, "--operator", "admin",
                env={**os.environ, "CALBENCH_PASSWORD": PW[login]})
        only = set(sys.argv[1:])
        srv = Server(work, db)
        servers.append(srv)
        cases = [("backlog", lambda: backlog_and_burst(srv)), ("slow", lambda: slow_clients(srv)), ("flood", lambda: header_flood(srv)),
                 ("streams", lambda: live_streams(srv)), ("cap", lambda: stream_cap(work, db)),
                 ("token", lambda: login_token(srv)), ("parallel", lambda: parallel_guesses(srv, db)),
                 ("role", lambda: role_change(srv, db, work)), ("tls", lambda: tls(work, db)),
                 ("conncap", lambda: connection_cap(work, db)),
                 ("address", lambda: address_limit(work, db))]
        for name, case in cases:
            if not only or name in only:
                case()
                print(f"{name}: ok")
        print("console security limits: ok")
    finally:
        for s in servers:
            s.stop()
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
