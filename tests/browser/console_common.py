"""What the console's browser tests share (console_test.py on SQLite, console_pg_test.py on
PostgreSQL): the calbench runner, a free port, raw HTTP beside the browser, Chromium through
Selenium, and following a slot of the live view until its run ends."""
import http.client
import os
import re
import shutil
import time
import urllib.parse

from selenium import webdriver
from selenium.webdriver.chrome.service import Service as ChromeService
from selenium.common.exceptions import StaleElementReferenceException, WebDriverException
from selenium.webdriver.common.by import By
from selenium.webdriver.support import expected_conditions as EC
from selenium.webdriver.support.ui import WebDriverWait

from calbench_cli import CB, SRC, free_port, run  # noqa: F401 (re-exported to the browser tests)
# The live run's plan: an operator prompt (slot 1) before a 6-s rate step.
PROMPT_PLAN = os.path.join(SRC, "tests/data/prompt_plan.toml")


class Http:
    """Raw requests beside the browser (forged forms, traversal): http.client, no redirects
    followed, cookies by hand. req() returns (status, body, Set-Cookie)."""

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
        csrf = re.search(r'name="csrf" value="([0-9a-f.]+)"', body).group(1)
        return self.req("POST", "/login", {"csrf": csrf, "login": user, "password": pw}, f"calbench_login={pre}")

    def wait_listening(self):
        for _ in range(100):
            try:
                self.req("GET", "/login")
                return
            except OSError:
                time.sleep(0.1)


def chromium(page_load_timeout=60):
    opts = webdriver.ChromeOptions()
    for a in ("--headless", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu"):
        opts.add_argument(a)
    if shutil.which("chromium"):
        opts.binary_location = shutil.which("chromium")
    d = webdriver.Chrome(service=ChromeService(executable_path=shutil.which("chromedriver")), options=opts)
    d.set_page_load_timeout(page_load_timeout)
    return d


def fresh(read, attempts=20):
    """read() again when the live table was redrawn under it (server-sent events replace it every
    few seconds: heartbeats, times left)."""
    for attempt in range(attempts):
        try:
            return read()
        except StaleElementReferenceException:
            if attempt == attempts - 1:
                raise


def page_left(old):
    """A WebDriverWait condition: the page `old` (its html element) belongs to has been replaced.
    Chromium reports an element of a document navigated away from either as stale or, while the new
    document loads, as "Node with given id does not belong to the document" (a plain
    WebDriverException, which EC.staleness_of does not take for staleness): both mean the page left."""
    def gone(_):
        try:
            old.is_enabled()
            return False
        except StaleElementReferenceException:
            return True
        except WebDriverException as e:
            if "does not belong to the document" in str(e):
                return True
            raise
    return gone


def click_and_wait(d, id_, timeout_s):
    """Click the button with this id and wait for the page it leads to (the old page goes)."""
    old = d.find_element(By.TAG_NAME, "html")
    d.find_element(By.ID, id_).click()
    WebDriverWait(d, timeout_s).until(page_left(old))


def confirm_prompt(d, pid):
    """Press a prompt's confirm button on /live and wait for the page it leads to. The live table is
    redrawn by server-sent events every few seconds (heartbeats, times left), so a button found just
    before a redraw is gone: find it again."""
    old = d.find_element(By.TAG_NAME, "html")
    for attempt in range(20):
        try:
            d.find_element(By.CSS_SELECTOR, f"#live .prompt[data-prompt='{pid}'] button.confirm").click()
            break
        except StaleElementReferenceException:
            if attempt == 19:
                raise
    WebDriverWait(d, 30).until(page_left(old))


def follow_slot(d, slot, timeout_s=120):
    """The (data-state, data-step) values a slot's row of /live goes through, as the page shows them
    (updated by server-sent events, never reloaded here), until the run ends or the time is up."""
    css = f"#live tr[data-slot='{slot}']"
    seen = []
    deadline = time.time() + timeout_s
    while time.time() < deadline:
        try:
            row = d.find_element(By.CSS_SELECTOR, css)
            st = (row.get_attribute("data-state"), row.get_attribute("data-step"))
        except Exception:  # replaced between the find and the read
            continue
        if not seen or seen[-1] != st:
            seen.append(st)
        if st[0] in ("passed", "failed", "aborted"):
            break
        time.sleep(0.1)
    return seen
