#!/usr/bin/python3
"""What the live page makes of given API answers, in a real browser (Debian's chromium,
headless): the page is the one the daemon serves, the answers are the daemon's own, altered to
show the two cases of issue 25 on demand.

1. The index tile showed "- / -" while the index chart showed values: the status's index is null
   whenever the newest wavelet window holds a gap (a missed cycle), which on a loaded machine is
   much of the time. The tile must show the newest value of its trend, as the chart does.
2. A loaded machine's `overrun` events (one a second at most) filled the event list and pushed
   the alarm out of sight. Repeated ones must fold into one row with a count.

Starts `leakmon run` on the simulated rig, takes the page's files and one answer of /api/trend
and /api/events from it, stops it, and serves those (altered) from a scripted server the
browser then reads.

    live_page_scripted_test.py --leakmon build/bin/leakmon --workdir DIR
"""
import argparse
import copy
import http.server
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
import urllib.parse

from selenium.webdriver.common.by import By

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from browser_page import free_port, headless_chromium, http_get, wait_for  # noqa: E402

CONFIG = """\
drivers: [{{name: rig, type: sim, scenario: healthy, seed: 7}}]
sampling: [{{name: main, period_ms: 2, drivers: [rig], priority: 0}}]
actuators:
  - name: cylinder
    channels: {{p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x, xref: rig.xref}}
    detector: {{kind: default, options: {{settle_seconds: 1, learn_seconds: 30}}}}
metrics: {{port: {port}, trend_interval_s: 0.5}}
state: {{directory: ""}}
worker: {{priority: 0}}
realtime: {{cpu_wakeup_latency_us: -1}}
"""
ASSETS = ["/", "/live.js", "/live.css", "/favicon.svg", "/uplot.min.js", "/uplot.min.css"]


def newest_finite(column):
    return next((v for v in reversed(column) if v is not None and math.isfinite(v)), None)


def daemon_answers(leakmon, workdir):
    """The page's files and one /api/trend and /api/events answer, from a running daemon."""
    port = free_port()
    config = os.path.join(workdir, "leakmon.yaml")
    with open(config, "w") as f:
        f.write(CONFIG.format(port=port))
    base = f"http://127.0.0.1:{port}"
    with open(os.path.join(workdir, "daemon.log"), "w") as log:
        daemon = subprocess.Popen([leakmon, "run", "--config", config], stdout=log, stderr=log)
        try:
            def trend_with_index():
                trend = json.loads(http_get(base + "/api/trend?since=0")[0])
                series = trend["actuators"][0]["trend"]
                finite = [v for v in series["index_p1_pa"] if v is not None]
                return trend if len(finite) >= 3 and newest_finite(series["p1_pa"]) else None
            trend = wait_for("three trend points with an index", trend_with_index, 90)
            events = json.loads(http_get(base + "/api/events?after=0")[0])
            assets = {path: http_get(base + path) for path in ASSETS}
        finally:
            daemon.send_signal(signal.SIGTERM)
            daemon.wait(timeout=15)
    return trend, events, assets


def scripted(trend, events):
    """The answers of the two cases: the newest index null, overruns around an alarm."""
    first = copy.deepcopy(trend)
    actuator = first["actuators"][0]
    for key in ("index_p1_pa", "index_p2_pa", "p1_pa", "p2_pa"):
        actuator[key] = None  # the newest window holds a gap
    later = copy.deepcopy(first)
    for column in later["actuators"][0]["trend"]:
        later["actuators"][0]["trend"][column] = []
    for group in later["groups"]:
        if group.get("trend"):
            for column in group["trend"]:
                group["trend"][column] = []

    started = events["events"][0]
    assert started["event"]["event"] == "daemon_started", events
    template = started["event"]

    def event(seq, **fields):
        e = {k: v for k, v in template.items() if k in ("time",)}
        e.update(fields)
        return {"seq": seq, "event": e}

    items = [started]
    seq = started["seq"]
    for n in range(2):
        seq += 1
        items.append(event(seq, event="overrun", channel="main",
                           message=f"{n + 1} overrun(s), {n} missed cycle(s) in total, 0 ring drop(s)"))
    seq += 1
    items.append(event(seq, event="alarm_raised", actuator="cylinder", alarm="internal_leakage",
                       channel="p1", score=1.5, leak_lpm_per_mpa=0.15))
    for n in range(6):
        seq += 1
        items.append(event(seq, event="overrun", channel="main",
                           message=f"{n + 3} overrun(s), {n + 2} missed cycle(s) in total, 0 ring drop(s)"))
    return first, later, {"events": items}, seq


def serve(assets, first_trend, later_trend, events, last_seq):
    trend_calls = [0]

    class Handler(http.server.BaseHTTPRequestHandler):
        def log_message(self, *args):
            pass

        def reply(self, body, content_type):
            self.send_response(200)
            self.send_header("Content-Type", content_type)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def do_GET(self):
            url = urllib.parse.urlparse(self.path)
            query = urllib.parse.parse_qs(url.query)
            if url.path == "/api/trend":
                answer = first_trend if trend_calls[0] == 0 else later_trend
                trend_calls[0] += 1
                self.reply(json.dumps(answer).encode(), "application/json")
            elif url.path == "/api/events":
                after = int(query.get("after", ["0"])[0])
                answer = events if after < last_seq else {"events": []}
                self.reply(json.dumps(answer).encode(), "application/json")
            elif url.path in assets:
                body, content_type = assets[url.path]
                self.reply(body, content_type)
            else:
                self.send_error(404)

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--leakmon", required=True)
    parser.add_argument("--workdir", required=True)
    args = parser.parse_args()
    os.makedirs(args.workdir, exist_ok=True)

    trend, events, assets = daemon_answers(args.leakmon, args.workdir)
    first, later, script, last_seq = scripted(trend, events)
    series = trend["actuators"][0]["trend"]
    expected_index = (f"{newest_finite(series['index_p1_pa']) / 1e3:.2f} / "
                      f"{newest_finite(series['index_p2_pa']) / 1e3:.2f}")
    expected_pressure = (f"{newest_finite(series['p1_pa']) / 1e6:.2f} / "
                         f"{newest_finite(series['p2_pa']) / 1e6:.2f}")
    server = serve(assets, first, later, script, last_seq)
    base = f"http://127.0.0.1:{server.server_address[1]}/"

    driver = headless_chromium("1400,1000")
    failures = []

    def check(condition, message):
        print(("ok   " if condition else "FAIL ") + message)
        if not condition:
            failures.append(message)

    try:
        driver.get(base)
        card = wait_for("the actuator's card",
                        lambda: driver.find_element(By.ID, "actuator-cylinder"), 15)
        wait_for("the trend on the page", lambda: int(card.get_attribute("data-points")) > 0, 10)
        tiles = card.find_elements(By.CSS_SELECTOR, ".tile .value")
        index_tile, pressure_tile = tiles[0].text, tiles[3].text
        check(index_tile == expected_index,
              f"index tile shows the newest index of its chart: {index_tile!r} "
              f"(expected {expected_index!r})")
        check(pressure_tile == expected_pressure,
              f"pressure tile likewise: {pressure_tile!r} (expected {expected_pressure!r})")

        rows = wait_for("the events", lambda: (r := driver.find_elements(
            By.CSS_SELECTOR, "#events tbody tr")) and len(r) >= 4 and r, 10)
        time.sleep(2.5)  # another poll must not add or duplicate rows
        rows = driver.find_elements(By.CSS_SELECTOR, "#events tbody tr")
        kinds = [row.find_elements(By.TAG_NAME, "td")[1].text for row in rows]
        check(kinds == ["overrun ×6", "alarm_raised", "overrun ×2", "daemon_started"],
              f"repeated overruns fold into one row each side of the alarm: {kinds}")
        newest_detail = rows[0].find_elements(By.TAG_NAME, "td")[4].text
        check("8 overrun(s)" in newest_detail, f"the folded row shows the newest: {newest_detail!r}")
        alarm = driver.find_element(By.CSS_SELECTOR, "#events tr.alarm_raised")
        check(alarm.is_displayed(), "the alarm stays in the list")
        errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
        check(not errors, f"no console errors ({errors})")
    finally:
        driver.quit()
        server.shutdown()
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
