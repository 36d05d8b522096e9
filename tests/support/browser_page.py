"""What the live-page browser tests share (tests/views/live_page_test.py and
live_page_scripted_test.py): a free local port, plain HTTP GETs, polling with a named timeout,
and headless chromium through chromedriver with its console log kept."""
import socket
import time
import urllib.request

from selenium import webdriver
from selenium.webdriver.chrome.service import Service


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def http_get(url):
    """The body (bytes) and Content-Type of a GET."""
    with urllib.request.urlopen(url, timeout=5) as response:
        return response.read(), response.headers.get("Content-Type")


def http_text(url):
    return http_get(url)[0].decode()


def wait_for(what, condition, timeout_s):
    """condition()'s first true value; exceptions count as "not yet" (the daemon or the page is
    not there yet)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            value = condition()
            if value:
                return value
        except Exception:  # not there yet
            pass
        time.sleep(0.25)
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")


def headless_chromium(window_size):
    """Debian's chromium, headless, WIDTH,HEIGHT; the browser console kept for get_log."""
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 f"--window-size={window_size}", "--no-first-run", "--disable-extensions"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
