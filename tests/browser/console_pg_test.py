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
  st2  (psql only)  calbench_station: another station's login, for the row-level security of the live rows
The set: bench/multipos/sim_effects.py → import imu-tk → fit multipos → db store-bench with its QC,
stored by qc1 (credentials from a PGPASSFILE). `calbench serve` gets the URI without user or password.

Paths: a wrong password is refused with the database's refusal and no session; st1 sees the queue,
opens the set, presses approve and is refused by the database (the set stays draft, read back with
`calbench db show --json` as qc2); qc1, its creator, is refused by four-eyes; qc2 approves; the
status is approved (CLI); the audit log shows the approval signed by Rita Review (login qc2). The
live view, as qc2: st1 runs an emulated two-slot `station run --db postgresql://…?user=st1` (slot 2
the wrong part, an operator prompt before the rate step; the run through a journal); /live shows the
prompt, slot 2 failed (PROD_ID), the rows stamped "by login st1" with a fresh heartbeat; psql as qc2
and as st2 cannot change st1's rows; qc2 confirms from the page, a second answer is 409 "no longer
waiting", and the page follows slot 1 to passed without a reload; the station exits 1. Log out. HTTP statuses are checked beside the browser with http.client. The server's log holds no password.

Run by ctest (tests/CMakeLists.txt: browser.console_pg) with CALBENCH and SRC set; exit 77 when
Chromium, chromedriver, Selenium or the PostgreSQL server binaries are missing (scripts/setup
installs them)."""
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

try:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service as ChromeService
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as EC
    from selenium.webdriver.support.ui import WebDriverWait
except ImportError:
    print("python3-selenium not installed: skipped")
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from console_common import CB, PROMPT_PLAN, SRC, Http, chromium, click_and_wait, confirm_prompt, follow_slot, free_port, fresh, run  # noqa: E402
if not (shutil.which("chromedriver") and (shutil.which("chromium") or shutil.which("chromium-browser"))):
    print("chromium / chromedriver not installed: skipped")
    sys.exit(77)
PG_BIN = os.environ.get("PG_BIN") or (sorted(glob.glob("/usr/lib/postgresql/*/bin")) or [""])[-1]
if not (os.access(os.path.join(PG_BIN, "initdb"), os.X_OK) and shutil.which("psql")):
    print("PostgreSQL server binaries or psql not installed: skipped")
    sys.exit(77)

PG_SERVER = os.path.join(SRC, "tests/support/pg_server.sh")


def live_run(d, http, base, work, pgport, env, text, admin, psql_as):
    """The live view on PostgreSQL, seen by a QC login (qc2, logged in): st1 runs an emulated
    two-slot station run with a PostgreSQL --db (the run through a local journal, the progress rows
    and the prompt written directly as st1); slot 2's unit is the wrong part. The page shows the
    prompt, slot 2 failed (PROD_ID), the rows stamped with st1 by the server and a live heartbeat;
    qc2 confirms from the page, which then follows slot 1 through the rate step to 'passed' without
    a reload. A second answer is refused (409); the rows cannot be changed by another login (grants,
    row-level security)."""
    plan = PROMPT_PLAN
    slog_path = os.path.join(work, "station.log")
    slog = open(slog_path, "w")
    station_env = {**env, "CALBENCH_JOURNAL": os.path.join(work, "journal.db"), "CALBENCH_STATION": "line-7"}
    station = subprocess.Popen([CB, "station", "run", "--plan", plan, "--emulated", "--pace", "1", "--units", "2", "--inject",
                                "2:imu-prod-id=0x1234", "--db", f"postgresql://127.0.0.1:{pgport}/calbench?user=st1",
                                "--out", os.path.join(work, "station-out")],
                               stdout=slog, stderr=subprocess.STDOUT, env=station_env, stdin=subprocess.DEVNULL)

    def station_log():
        slog.flush()
        return open(slog_path).read()

    try:
        d.get(base + "/live")
        slot = lambda n: f"#live tr[data-slot='{n}']"
        try:  # the prompt appears without a reload (the run reaches it after step 1)
            prompt = WebDriverWait(d, 90).until(EC.presence_of_element_located((By.CSS_SELECTOR, "#live .prompt")))
        except Exception:
            raise SystemExit("no prompt on /live: " + d.find_element(By.TAG_NAME, "main").text[:800]
                             + "\n--- station log:\n" + station_log()[-2000:])
        def read_live():  # every value of the fragment from one version of it
            pr = d.find_element(By.CSS_SELECTOR, "#live .prompt")
            s1 = d.find_element(By.CSS_SELECTOR, slot(1))
            s2 = d.find_element(By.CSS_SELECTOR, slot(2))
            return {"prompt": pr.text, "live": d.find_element(By.ID, "live").text,
                    "started": d.find_element(By.CSS_SELECTOR, "#live section.run p.muted").text,
                    "s1": s1.text, "s1_state": s1.get_attribute("data-state"),
                    "s1_check": s1.find_element(By.CSS_SELECTOR, "td.check").text,
                    "s1_beat": s1.find_elements(By.CSS_SELECTOR, "td")[-1].text,
                    "s2": s2.text, "s2_state": s2.get_attribute("data-state"),
                    "s2_why": s2.find_element(By.CSS_SELECTOR, "td.why").text,
                    "pid": pr.get_attribute("data-prompt"),
                    "csrf": pr.find_element(By.CSS_SELECTOR, "form input[name=csrf]").get_attribute("value")}
        v = fresh(read_live)
        assert "turn the fixture's clamp in slot 1" in v["prompt"], v["prompt"]
        assert "line-7" in v["live"], v["live"][:800]
        # The server stamps who wrote the rows: the station's login.
        assert "by login st1" in v["started"], v["started"]
        assert v["s1_state"] == "waiting", v["s1"]
        assert v["s1_check"].startswith("0 ≤ 0"), v["s1"]
        beat = v["s1_beat"]  # the heartbeat column: parsed, fresh
        assert re.fullmatch(r"\d+ s ago", beat) and int(beat.split()[0]) < 30, f"heartbeat {beat!r}: {v['s1']}"
        assert v["s2_state"] == "failed", v["s2"]
        assert "PROD_ID" in v["s2_why"], v["s2"]
        pid = v["pid"]
        cookie = "calbench_session=" + d.get_cookie("calbench_session")["value"]
        csrf = v["csrf"]
        # In the store: every row written as st1 (stamped by the server), the prompt asked by st1.
        assert admin("calbench", "SELECT string_agg(DISTINCT login, ',') FROM station_progress") == "st1"
        assert admin("calbench", f"SELECT created_login || '|' || state FROM station_prompts WHERE id = {pid}") == "st1|waiting"
        # Nobody else changes st1's rows: a QC login has no UPDATE grant, another station login's
        # UPDATE finds no row of its own (row-level security).
        rc, out, err = psql_as("qc2", "UPDATE station_progress SET state = 'failed', reason = 'forged by qc2'")
        assert rc != 0 and "permission denied" in err, (rc, out, err)
        rc, out, err = psql_as("st2", "UPDATE station_progress SET state = 'failed', reason = 'forged by st2'")
        assert rc == 0 and out.strip() == "UPDATE 0", (rc, out, err)
        states = admin("calbench", "SELECT string_agg(slot || '=' || state || '@' || login, ',' ORDER BY slot) FROM station_progress")
        assert states == "1=waiting@st1,2=failed@st1", states
        assert station.poll() is None, "the run ended without its prompt answered:\n" + station_log()[-2000:]
        # Answer from the page. The heartbeat changes the fragment every 0.5 s and the page's script
        # replaces it: a button found just before a replacement is stale, so find it again.
        confirm_prompt(d, pid)
        if not d.find_elements(By.ID, "done"):
            raise SystemExit("confirming the prompt failed: " + d.find_element(By.TAG_NAME, "main").text[:1200]
                             + "\n--- station log:\n" + station_log()[-2000:])
        assert "confirmed by Rita Review" in text("done"), text("done")
        page = d.find_element(By.TAG_NAME, "html")
        # A second answer (the same page posted again, with a valid token) is refused.
        st, body, _ = http.req("POST", f"/prompt/{pid}/confirm", {"csrf": csrf}, cookie)
        assert st == 409 and "no longer waiting" in body, (st, body[:600])
        st, body, _ = http.req("POST", f"/prompt/{pid}/reject", {"csrf": csrf, "reason": "too late"}, cookie)
        assert st == 409 and "no longer waiting" in body, (st, body[:600])
        answered = admin("calbench", f"SELECT state || '|' || answered_by || '|' || answered_login FROM station_prompts WHERE id = {pid}")
        assert answered == "confirmed|Rita Review|qc2", answered
        # The page follows slot 1 (server-sent events, no reload) through the rate step to passed.
        seen = follow_slot(d, 1)
        assert seen and seen[-1][0] == "passed", (seen, station_log()[-2000:])
        assert ("running", "1") in seen, f"the rate step was never seen running: {seen}"
        page.tag_name  # raises StaleElementReferenceException if the page was reloaded
        beat = d.find_element(By.CSS_SELECTOR, slot(1)).find_elements(By.CSS_SELECTOR, "td")[-1].text
        assert re.fullmatch(r"\d+ s ago", beat), f"heartbeat {beat!r}"
        rc = station.wait(60)
        assert rc == 1, f"one of two units failed: exit 1, not {rc}\n" + station_log()[-2000:]
    finally:
        if station.poll() is None:
            station.kill()
            station.wait()
        slog.close()
    log = open(slog_path).read()
    assert "confirmed by Rita Review" in log, log[-2000:]
    assert "live view off" not in log and "live view: could not" not in log, log[-2000:]
    assert re.search(r"forwarded to postgresql://127\.0\.0\.1:\d+/calbench\?user=st1: 1001 run \d+ \(pass\)", log), log[-2000:]
    states = admin("calbench", "SELECT string_agg(slot || '=' || state || '@' || login, ',' ORDER BY slot) FROM station_progress")
    assert states == "1=passed@st1,2=failed@st1", states


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
        pw = {login: f"pw-{login}-{secrets.token_hex(8)}" for login in ("st1", "st2", "qc1", "qc2")}
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
        admin("calbench", "GRANT calbench_station TO st2")  # another station's login (psql only: row-level security)

        def psql_as(login, sql):
            """Plain psql over TCP as a login (its password from the PGPASSFILE): rc, stdout, stderr."""
            q = subprocess.run(["psql", "-h", "127.0.0.1", "-p", str(pgport), "-U", login, "-d", "calbench", "-X",
                                "-v", "ON_ERROR_STOP=1", "-c", sql], capture_output=True, text=True, env=env)
            return q.returncode, q.stdout, q.stderr

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

        driver = chromium(60)
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
            click_and_wait(d, id_, 60)

        def session_and_csrf():
            cookie = "calbench_session=" + d.get_cookie("calbench_session")["value"]
            csrf = d.find_element(By.CSS_SELECTOR, "form[action='/logout'] input[name=csrf]").get_attribute("value")  # every page's
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

        # Station login: sees the queue, opens the set, is offered no approve button (issue 56 item 13);
        # a forged approval is refused by the database.
        login("st1", pw["st1"])
        assert "Sam Station" in text("who") and "st1" in text("who"), text("who")
        rows = d.find_elements(By.CSS_SELECTOR, "#queue tr[data-set]")
        assert [r.get_attribute("data-set") for r in rows] == [set_id], [r.get_attribute("data-set") for r in rows]
        rows[0].find_element(By.CSS_SELECTOR, "a.open").click()
        assert text("status") == "draft", text("status")
        cookie, csrf = session_and_csrf()
        assert not d.find_elements(By.ID, "approve"), "a station login is offered approve"
        assert "station account" in text("no-sign"), text("no-sign")
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

        # The live view: st1's station run on PostgreSQL, its prompt answered by qc2 from /live.
        live_run(d, http, base, work, pgport, env, text, admin, psql_as)
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
