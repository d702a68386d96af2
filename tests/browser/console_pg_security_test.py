#!/usr/bin/python3
"""The PostgreSQL console's security limits (issue 54 items 8, 9, 11) by raw HTTP, on a throw-away
PostgreSQL server (tests/support/pg_server.sh; max_connections 60):

* 70 sessions of one login with --db-connections 4: every session is served, the console never has
  more than 4 connections open, psql and the CLI still connect, and the login is not locked;
* the database refusing connections (too many for the role): log-in attempts are answered 503 "try
  again" and do not count as failed logins (6 of them, then the right password logs in);
* a wrong password is a failed login (401), in the server's log with login and address, never with
  the password;
* a role change (qc to station in calbench_users, as `db user add` makes it) ends the login's open sessions at their next
  request; a station's refused approval is audited by the database (calbench_audit_security).

Run by ctest (browser.console_pg_security) with CALBENCH and SRC set; exit 77 without the PostgreSQL
server binaries."""
import glob
import json
import os
import re
import secrets
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from console_security_test import Server  # noqa: E402

from calbench_cli import SRC, run  # noqa: E402
PG_BIN = os.environ.get("PG_BIN") or (sorted(glob.glob("/usr/lib/postgresql/*/bin")) or [""])[-1]
if not (os.access(os.path.join(PG_BIN, "initdb"), os.X_OK) and shutil.which("psql")):
    print("PostgreSQL server binaries or psql not installed: skipped")
    sys.exit(77)
PG_SERVER = os.path.join(SRC, "tests/support/pg_server.sh")


class Pg:
    """The throw-away server: its port, psql as the superuser, the logins' passwords, the set."""

    def __init__(self, work, pgdir, port):
        self.work, self.dir, self.port = work, pgdir, port

    def admin(self, dbname, sql):
        q = subprocess.run(["psql", "-h", self.dir, "-p", str(self.port), "-U", "calbench_admin", "-d", dbname, "-v",
                            "ON_ERROR_STOP=1", "-qtAX", "-c", sql], capture_output=True, text=True)
        if q.returncode != 0:
            raise SystemExit(f"psql {sql!r}: exit {q.returncode}\n{q.stderr}")
        return q.stdout.strip()

    def setup(self):
        self.admin("postgres", "CREATE DATABASE calbench")
        admin_uri = f"postgresql:///calbench?host={self.dir}&port={self.port}&user=calbench_admin"
        run("db", "init", "--db", admin_uri, "--roles", "--operator", "admin")
        self.admin_uri = admin_uri
        self.pw = {login: f"pw-{login}-{secrets.token_hex(8)}" for login in ("st1", "qc1", "qc2")}
        for login, secret in self.pw.items():
            self.admin("calbench", f"CREATE ROLE {login} LOGIN PASSWORD '{secret}'")
        for login, name, role in (("st1", "Sam Station", "station"), ("qc1", "Quinn QA", "qc"), ("qc2", "Rita Review", "qc")):
            run("db", "user", "add", login, "--db", admin_uri, "--name", name, "--role", role, "--operator", "admin")
        # A draft set, stored by qc1 (also a station login, so that it may store) with its password.
        self.admin("calbench", "GRANT calbench_station TO qc1")
        pgpass = os.path.join(self.work, "pgpass")
        with open(pgpass, "w") as f:
            f.write(f"127.0.0.1:{self.port}:calbench:qc1:{self.pw['qc1']}\n")
        os.chmod(pgpass, 0o600)
        sim, rec, coeffs = (os.path.join(self.work, n) for n in ("sim", "rec", "c.json"))
        subprocess.run([sys.executable, os.path.join(SRC, "bench/multipos/sim_effects.py"), sim, "--seed", "504", "--poses", "24"],
                       check=True, capture_output=True)
        run("import", "imu-tk", f"{sim}/acc.txt", f"{sim}/gyro.txt", "--out", rec, "--model", "ADIS16488A", "--serial", "SIMQ1",
            "--site-lat", "52")
        fit = json.loads(run("fit", "multipos", rec, "--out", coeffs, "--json").stdout)["multipos"]
        run("db", "store-bench", "--db", f"postgresql://qc1@127.0.0.1:{self.port}/calbench", "--coeffs", coeffs, "--recording", rec,
            "--operator", "Quinn QA", "--qc", f"g_loo_rms={fit['g_loo_rms_m_s2']}:{fit['qc_g_loo_limit_m_s2']}:m/s2:out-of-sample",
            env={**os.environ, "PGPASSFILE": pgpass})
        self.set_id = self.admin("calbench", "SELECT max(id) FROM coefficient_sets")

    def console_connections(self):
        """The console's connections: the smaller of two readings 0.3 s apart (a backend whose
        connection was just closed may still be listed for a moment)."""
        def count():
            return int(self.admin("postgres", "SELECT count(*) FROM pg_stat_activity WHERE application_name = 'calbench' "
                                              "AND usename IN ('st1', 'qc1', 'qc2')"))
        first = count()
        time.sleep(0.3)
        return min(first, count())


def pool(pg, srv):
    """Item 11: 70 sessions (more than max_connections 60), each served, at most 4 connections."""
    sessions, most = [], 0
    for i in range(70):
        sessions.append(srv.session("qc2"))
        if i % 10 == 9:
            most = max(most, pg.console_connections())
    for ck in sessions:
        st, body, _ = srv.req("GET", "/queue", cookie=ck)
        assert st == 200 and 'id="queue"' in body, (st, body[:300])
    most = max(most, pg.console_connections())
    print(f"70 sessions of qc2 served; console connections at most {most} (--db-connections 4)")
    assert most <= 4, most
    q = subprocess.run(["psql", f"postgresql://qc1:{pg.pw['qc1']}@127.0.0.1:{pg.port}/calbench", "-qtAXc", "SELECT 1"],
                       capture_output=True, text=True)
    assert q.returncode == 0 and q.stdout.strip() == "1", q.stderr
    st, body, _ = srv.login("qc2", pg.pw["qc2"])
    assert st == 303, (st, body[:300])
    return sessions


def failures(pg, srv):
    """Item 9: a wrong password is a failed login, in the log with login and address, not the
    password. Item 11: the database refusing connections (too many for the role, SQLSTATE 53300, as
    when max_connections is exhausted) is the server's trouble, not a wrong password: 503, no lock-out."""
    st, body, _ = srv.login("qc1", "not-the-password-x")
    assert st == 401 and "password authentication failed" in body, (st, body[:300])
    log = srv.logged()
    assert re.search(r"security login-failed login qc1: from 127\.0\.0\.1", log), log[-1500:]
    assert re.search(r"calbench serve: 127\.0\.0\.1 qc1 POST /login 401", log), log[-1500:]
    pg.admin("calbench", "ALTER ROLE qc1 CONNECTION LIMIT 0")
    out = [srv.login("qc1", pg.pw["qc1"]) for _ in range(6)]
    assert [o[0] for o in out] == [503] * 6 and "did not count" in out[0][1], [(o[0], o[1][:200]) for o in out]
    pg.admin("calbench", "ALTER ROLE qc1 CONNECTION LIMIT -1")
    st, body, _ = srv.login("qc1", pg.pw["qc1"])
    assert st == 303, (st, body[:300])


def role_change(pg, srv, older):
    """Item 8: qc2 becomes a station login: its sessions end at their next request. A station's
    approval is refused by the database and audited through its session's connection."""
    a, st1 = srv.session("qc2"), srv.session("st1")
    assert srv.req("GET", "/queue", cookie=a)[0] == 200
    run("db", "user", "add", "qc2", "--db", pg.admin_uri, "--name", "Rita Review", "--role", "station", "--operator", "admin")
    assert pg.admin("calbench", "SELECT pg_has_role('qc2', 'calbench_qc', 'MEMBER')") == "f"
    st, body, _ = srv.req("GET", "/queue", cookie=a)
    assert st == 401 and "session has ended" in body and "role" in body, (st, body[:400])
    assert srv.req("GET", "/queue", cookie=older)[0] in (303, 401)
    sid = pg.set_id
    st, body, _ = srv.req("POST", f"/set/{sid}/approve", {"csrf": srv.csrf(st1, f"/set/{sid}")}, st1)
    assert st == 403 and pg.admin("calbench", f"SELECT status FROM coefficient_sets WHERE id = {sid}") == "draft", (st, body[:300])
    rows = pg.admin("calbench", "SELECT action || '|' || detail || '|' || \"user\" FROM audit_log WHERE entity = 'security' ORDER BY id")
    assert re.search(r"^refused\|qc2: session ended .*role", rows, re.M), rows
    assert re.search(rf"^refused\|st1: set {sid} approve: .*\|Sam Station$", rows, re.M), rows


def main():
    work = tempfile.mkdtemp(prefix="calbench-console-pgsec-")
    pgdir = os.path.join(work, "pg")
    srv = None
    try:
        p = subprocess.run([PG_SERVER, "start", pgdir], capture_output=True, text=True)
        if p.returncode == 77:
            print("no PostgreSQL: skipped")
            sys.exit(77)
        if p.returncode != 0:
            raise SystemExit(f"pg_server.sh start: exit {p.returncode}\n{p.stderr}")
        pg = Pg(work, pgdir, int(p.stdout.strip()))
        pg.setup()
        import console_security_test as cst
        cst.PW = pg.pw
        srv = Server(work, f"postgresql://127.0.0.1:{pg.port}/calbench", "--db-connections", "4")
        sessions = pool(pg, srv)
        failures(pg, srv)
        role_change(pg, srv, sessions[0])
        log = srv.logged()
        for secret in (*pg.pw.values(), "not-the-password-x"):
            assert secret not in log, "a password reached the log"
        print("console on PostgreSQL, security limits: ok")
    finally:
        if srv:
            srv.stop()
        subprocess.run([PG_SERVER, "stop", pgdir], capture_output=True)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
