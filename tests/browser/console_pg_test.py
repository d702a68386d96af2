#!/usr/bin/python3
"""The web console (`calbench serve`, issue 38) in a real browser on a PostgreSQL store: Debian's
Chromium driven by Selenium (python3-selenium, chromium-driver) against a throw-away PostgreSQL server
(tests/support/pg_server.sh: initdb + pg_ctl in a temporary folder, free loopback port, stopped in
every exit path). Every console request runs as the database login that logged in, so the refusals
seen in the browser are the database's own, as on the command line.

Logins (made with CREATE ROLE ... LOGIN PASSWORD, mapped with `calbench db user add`):
  st1  Sam Station  calbench_station
  qc1  Quinn QA     calbench_qc, and calbench_station so that it may store the set (it is its creator)
  qc2  Rita Review  calbench_qc
The set: bench/multipos/sim_effects.py → import imu-tk → fit multipos → db store-bench with its QC,
stored by qc1 (credentials from a PGPASSFILE). `calbench serve` gets the URI without user or password.

Paths: a wrong password is refused with the database's refusal and no session; st1 sees the queue,
opens the set, presses approve and is refused by the database (the set stays draft, read back with
`calbench db show --json` as qc2); qc1, its creator, is refused by four-eyes; qc2 approves; the
status is approved (CLI); the audit log shows the approval signed by Rita Review (login qc2); log
out. HTTP statuses are checked beside the browser with http.client. The server's log holds no password.

Run by ctest (tests/CMakeLists.txt: browser.console_pg) with CALBENCH and SRC set; exit 77 when
Chromium, chromedriver, Selenium or the PostgreSQL server binaries are missing (scripts/setup
installs them)."""
import glob
import http.client
import json
import os
import re
import secrets
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.parse

try:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service as ChromeService
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as EC
    from selenium.webdriver.support.ui import WebDriverWait
except ImportError:
    print("python3-selenium not installed: skipped")
    sys.exit(77)

CB = os.environ["CALBENCH"]
SRC = os.environ["SRC"]
if not (shutil.which("chromedriver") and (shutil.which("chromium") or shutil.which("chromium-browser"))):
    print("chromium / chromedriver not installed: skipped")
    sys.exit(77)
PG_BIN = os.environ.get("PG_BIN") or (sorted(glob.glob("/usr/lib/postgresql/*/bin")) or [""])[-1]
if not (os.access(os.path.join(PG_BIN, "initdb"), os.X_OK) and shutil.which("psql")):
    print("PostgreSQL server binaries or psql not installed: skipped")
    sys.exit(77)

PG_SERVER = os.path.join(SRC, "tests/support/pg_server.sh")


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


class Http:
    """Raw requests beside the browser: http.client, no redirects followed, cookies by hand."""

    def __init__(self, port):
        self.port = port

    def req(self, method, path, body=None, cookie=None):
        c = http.client.HTTPConnection("127.0.0.1", self.port, timeout=30)
        h = {}
        if cookie:
            h["Cookie"] = cookie
        if body is not None:
            h["Content-Type"] = "application/x-www-form-urlencoded"
            body = urllib.parse.urlencode(body)
        c.request(method, path, body=body, headers=h)
        r = c.getresponse()
        out = (r.status, r.read().decode("utf-8", "replace"), r.getheader("Set-Cookie") or "")
        c.close()
        return out

    def login(self, user, pw):
        """The login form as a browser posts it: its double-submit CSRF cookie and field."""
        st, body, setc = self.req("GET", "/login")
        assert st == 200, st
        pre = re.search(r"calbench_login=([0-9a-f]+)", setc).group(1)
        csrf = re.search(r'name="csrf" value="([0-9a-f]+)"', body).group(1)
        return self.req("POST", "/login", {"csrf": csrf, "login": user, "password": pw}, f"calbench_login={pre}")


def main():
    work = tempfile.mkdtemp(prefix="calbench-console-pg-")
    pgdir = os.path.join(work, "pg")
    pg_started = False
    server = driver = None
    try:
        p = subprocess.run([PG_SERVER, "start", pgdir], capture_output=True, text=True)
        if p.returncode == 77:
            print("no PostgreSQL: skipped")
            sys.exit(77)
        pg_started = True  # stop it even when start failed half-way (pg_server.sh stop is best-effort)
        if p.returncode != 0:
            raise SystemExit(f"pg_server.sh start: exit {p.returncode}\n{p.stderr}")
        pgport = int(p.stdout.strip())

        def admin(dbname, sql):
            q = subprocess.run(["psql", "-h", pgdir, "-p", str(pgport), "-U", "calbench_admin", "-d", dbname,
                                "-v", "ON_ERROR_STOP=1", "-qtAX", "-c", sql], capture_output=True, text=True)
            if q.returncode != 0:
                raise SystemExit(f"psql {sql!r}: exit {q.returncode}\n{q.stderr}")
            return q.stdout.strip()

        admin("postgres", "CREATE DATABASE calbench")
        admin_uri = f"postgresql:///calbench?host={pgdir}&port={pgport}&user=calbench_admin"
        init = run("db", "init", "--db", admin_uri, "--roles", "--operator", "admin").stdout
        assert "schema version" in init, init

        # Logins with passwords; the CLI reads them from a PGPASSFILE, never from its command line.
        pw = {login: f"pw-{login}-{secrets.token_hex(8)}" for login in ("st1", "qc1", "qc2")}
        pgpass = os.path.join(work, "pgpass")
        with open(pgpass, "w") as f:
            for login, secret in pw.items():
                admin("calbench", f"CREATE ROLE {login} LOGIN PASSWORD '{secret}'")
                f.write(f"127.0.0.1:{pgport}:calbench:{login}:{secret}\n")
        os.chmod(pgpass, 0o600)
        env = {**os.environ, "PGPASSFILE": pgpass, "CALBENCH_STATION": "line-1"}
        for k in ("CALBENCH_OPERATOR", "CALBENCH_USER", "PGPASSWORD", "PGUSER"):
            env.pop(k, None)
        for login, name, role in (("st1", "Sam Station", "station"), ("qc1", "Quinn QA", "qc"), ("qc2", "Rita Review", "qc")):
            out = run("db", "user", "add", login, "--db", admin_uri, "--name", name, "--role", role, "--operator", "admin").stdout
            assert f"login {login} = {name}" in out and "added" in out, out
        admin("calbench", "GRANT calbench_station TO qc1")  # qc1 may store: it is the set's creator

        def uri(login):
            return f"postgresql://{login}@127.0.0.1:{pgport}/calbench"

        def show():
            return json.loads(run("db", "show", "SIMP1", "--db", uri("qc2"), "--json", env=env).stdout)["sets"]

        # The set, stored by qc1 over TCP with its password.
        sim = os.path.join(work, "sim")
        subprocess.run([sys.executable, os.path.join(SRC, "bench/multipos/sim_effects.py"), sim, "--seed", "502",
                        "--poses", "24"], check=True, capture_output=True)
        rec = os.path.join(work, "rec")
        run("import", "imu-tk", f"{sim}/acc.txt", f"{sim}/gyro.txt", "--out", rec, "--model", "ADIS16488A",
            "--serial", "SIMP1", "--site-lat", "52")
        coeffs = os.path.join(work, "c.json")
        fit = json.loads(run("fit", "multipos", rec, "--out", coeffs, "--json").stdout)["multipos"]
        run("db", "store-bench", "--db", uri("qc1"), "--coeffs", coeffs, "--recording", rec, "--operator", "Quinn QA", "--qc",
            f"g_loo_rms={fit['g_loo_rms_m_s2']}:{fit['qc_g_loo_limit_m_s2']}:m/s2:out-of-sample", env=env)
        sets = show()
        assert len(sets) == 1 and sets[0]["status"] == "draft", sets
        set_id = str(sets[0]["id"])
        creator = admin("calbench", f"SELECT created_by_role FROM coefficient_sets WHERE id = {set_id}")
        assert creator == "qc1", creator

        # The console: the URI without user or password; the log (stdout and stderr) kept apart.
        port = free_port()
        out_log = open(os.path.join(work, "serve.out"), "w")
        err_log = open(os.path.join(work, "serve.err"), "w")
        server = subprocess.Popen([CB, "serve", "--db", f"postgresql://127.0.0.1:{pgport}/calbench", "--listen", f"127.0.0.1:{port}"],
                                  stdout=out_log, stderr=err_log, env={k: v for k, v in env.items() if k != "PGPASSFILE"})
        base = f"http://127.0.0.1:{port}"
        http = Http(port)
        for _ in range(100):  # until it listens
            try:
                http.req("GET", "/login")
                break
            except OSError:
                if server.poll() is not None:
                    raise SystemExit("calbench serve ended: " + open(os.path.join(work, "serve.err")).read())
                time.sleep(0.1)

        opts = webdriver.ChromeOptions()
        for a in ("--headless", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu"):
            opts.add_argument(a)
        if shutil.which("chromium"):
            opts.binary_location = shutil.which("chromium")
        driver = webdriver.Chrome(service=ChromeService(executable_path=shutil.which("chromedriver")), options=opts)
        driver.set_page_load_timeout(60)
        d = driver

        def login(user, secret):
            d.get(base + "/login")
            d.find_element(By.ID, "login").send_keys(user)
            d.find_element(By.ID, "password").send_keys(secret)
            submit("submit")

        def logout():
            submit("logout")
            assert d.find_elements(By.ID, "password"), "log out did not return to the login form"
            assert d.get_cookie("calbench_session") is None, d.get_cookie("calbench_session")

        def text(id_):
            return WebDriverWait(d, 60).until(EC.presence_of_element_located((By.ID, id_))).text

        def submit(id_):
            """Click a form's button and wait for the page it leads to (the old page goes stale)."""
            old = d.find_element(By.TAG_NAME, "html")
            d.find_element(By.ID, id_).click()
            WebDriverWait(d, 60).until(EC.staleness_of(old))

        def session_and_csrf():
            cookie = "calbench_session=" + d.get_cookie("calbench_session")["value"]
            csrf = d.find_element(By.CSS_SELECTOR, f"form[action='/set/{set_id}/approve'] input[name=csrf]").get_attribute("value")
            return cookie, csrf

        # The login page says which logins it takes.
        d.get(base + "/queue")
        assert d.current_url.endswith("/login"), d.current_url
        assert "PostgreSQL login" in d.find_element(By.TAG_NAME, "main").text, d.find_element(By.TAG_NAME, "main").text

        # A wrong password: the database's refusal, no session (in the browser and by status).
        login("qc2", "not-the-password")
        err = text("error")
        assert "the database refused the login" in err and "password authentication failed" in err, err
        assert not d.find_elements(By.ID, "queue") and not d.find_elements(By.ID, "who")
        assert d.get_cookie("calbench_session") is None, d.get_cookie("calbench_session")
        st, body, setc = http.login("qc2", "also-not-it")
        assert st == 401 and "password authentication failed" in body and "calbench_session" not in setc, (st, setc, body[:400])
        st, body, setc = http.login("nobody", "whatever-pw")  # no such role: refused the same way
        assert st == 401 and "the database refused the login" in body and "calbench_session" not in setc, (st, body[:400])

        # Station login: sees the queue, opens the set, approve is refused by the database.
        login("st1", pw["st1"])
        assert "Sam Station" in text("who") and "st1" in text("who"), text("who")
        rows = d.find_elements(By.CSS_SELECTOR, "#queue tr[data-set]")
        assert [r.get_attribute("data-set") for r in rows] == [set_id], [r.get_attribute("data-set") for r in rows]
        rows[0].find_element(By.CSS_SELECTOR, "a.open").click()
        assert text("status") == "draft", text("status")
        cookie, csrf = session_and_csrf()
        submit("approve")
        err = text("error")
        assert "refused" in err and "st1" in err, "a station login approved a set: " + d.find_element(By.TAG_NAME, "main").text[:600]
        assert text("status") == "draft", text("status")
        assert show()[0]["status"] == "draft"
        st, body, _ = http.req("POST", f"/set/{set_id}/approve", {"csrf": csrf}, cookie)
        assert st == 403 and "st1" in body, (st, body[:400])
        assert show()[0]["status"] == "draft"
        logout()

        # qc1 stored the set: four-eyes refuses it.
        login("qc1", pw["qc1"])
        assert "Quinn QA" in text("who"), text("who")
        d.get(f"{base}/set/{set_id}")
        cookie, csrf = session_and_csrf()
        submit("approve")
        err = text("error")
        assert "four-eyes" in err and "qc1" in err, "the creator approved: " + d.find_element(By.TAG_NAME, "main").text[:600]
        assert text("status") == "draft", text("status")
        assert show()[0]["status"] == "draft"
        st, body, _ = http.req("POST", f"/set/{set_id}/approve", {"csrf": csrf}, cookie)
        assert st in (403, 409) and "four-eyes" in body, (st, body[:400])
        assert show()[0]["status"] == "draft"
        logout()

        # qc2: the queue with the verdict, the report inline, the approval signed as Rita Review.
        login("qc2", pw["qc2"])
        assert "Rita Review" in text("who") and "qc2" in text("who"), text("who")
        rows = d.find_elements(By.CSS_SELECTOR, "#queue tr[data-set]")
        assert [r.get_attribute("data-set") for r in rows] == [set_id], [r.get_attribute("data-set") for r in rows]
        assert "meets every threshold" in rows[0].text, rows[0].text
        rows[0].find_element(By.CSS_SELECTOR, "a.open").click()
        report = text("report")
        assert "Coefficient history" in report and "multi-position fit" in report, report[:400]
        submit("approve")
        done = text("done")
        assert f"set {set_id} approved" in done and "Rita Review" in done, done
        assert text("status") == "approved", text("status")
        sets = show()
        assert sets[0]["status"] == "approved", sets
        signer = admin("calbench", f"SELECT \"user\" || '|' || db_role FROM audit_log WHERE entity_id = {set_id} AND action = 'status'")
        assert signer == "Rita Review|qc2", signer
        d.get(base + "/audit")
        approval = [r.text for r in d.find_elements(By.CSS_SELECTOR, "#audit tr") if "draft -> approved" in r.text]
        assert len(approval) == 1 and "Rita Review" in approval[0] and "login qc2" in approval[0], \
            (approval, text("audit")[:800])
        cookie = "calbench_session=" + d.get_cookie("calbench_session")["value"]
        logout()
        st, body, _ = http.req("GET", "/queue", cookie=cookie)  # the session ended with the log-out
        assert st == 303, st
        st, body, _ = http.req("GET", "/queue")  # and none without a cookie
        assert st == 303, st

        # No password in the server's log (nor in its standard output).
        server.terminate()
        server.wait(10)
        out_log.close()
        err_log.close()
        logged_err = open(os.path.join(work, "serve.err")).read()
        logged = logged_err + open(os.path.join(work, "serve.out")).read()
        assert "POST /login 401" in logged_err and f"POST /set/{set_id}/approve" in logged_err, logged_err[:800]
        for secret in (*pw.values(), "not-the-password", "also-not-it", "whatever-pw"):
            assert secret not in logged, "a password reached the server's log"
        print("console on PostgreSQL in Chromium: ok")
    finally:
        if driver:
            driver.quit()
        if server and server.poll() is None:
            server.terminate()
            server.wait(10)
        if pg_started:
            subprocess.run([PG_SERVER, "stop", pgdir], capture_output=True)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
