#!/usr/bin/python3
"""The live page in a real browser (Debian's chromium, headless, through chromedriver).

Starts `leakmon run` on the simulated rig (a 0.15 l/min/MPa leak opens at 40 s; the detector
learns from 2 s for at least 12 s, longer until the steps have loaded the piston enough: up to
26 s was seen, and a leak opened at 20 s was then learned as healthy), opens http://127.0.0.1:PORT/ and checks, as an operator would see it:
the page loads everything from the daemon only and logs no console error (CSP violations
included), the trend advances, the leak alarm appears after the leak, and the page's
Acknowledge button changes the daemon's alarm state (read back from /metrics). A second,
pressure-only actuator on a rig held by seal friction must show the "blind" badge once it has
learned, and the first actuator must not. Optionally saves
a screenshot with the raised alarm (docs/figures/live-page.png is made this way).

The sampling loop asks for SCHED_FIFO as on a rig PC (granted to root, as in CI; otherwise the
daemon warns and runs with normal scheduling): on a loaded machine with normal scheduling the
loop missed thousands of cycles, each a gap that voids the press's index windows, and the press
then had not finished learning (nor said it is blind) when the test looked.

    live_page_test.py --leakmon build/bin/leakmon --workdir DIR [--screenshot FILE.png]
"""
import argparse
import os
import signal
import subprocess
import sys
import time

from selenium.webdriver.common.by import By

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from browser_page import free_port, headless_chromium, http_text, wait_for  # noqa: E402

LEAK_ONSET_S = 40.0
FRICTION_SCENARIO = """\
name: press-held-by-seal-friction
controller: basic
duration_s: 3600
seed: 9
effects:
  coulomb_friction: {F_C: 120}
"""

CONFIG = """\
drivers:
  - name: rig
    type: sim
    scenario: healthy
    seed: 7
    leak: {{lpm_per_mpa: 0.15, onset_s: {onset}, ramp_s: 1}}
  - name: press_rig
    type: sim
    scenario: {friction_scenario}
sampling:
  - {{name: main, period_ms: 2, drivers: [rig, press_rig], priority: 40}}
actuators:
  - name: cylinder
    channels: {{p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x, xref: rig.xref}}
    features: {{wavelet: db8, level: 2, window: 400, step: 20, mode: symmetric}}
    detector: {{kind: default, options: {{settle_seconds: 2, learn_seconds: 12}}}}
    alarm: {{on_delay_s: 1, off_delay_s: 10, latching: false}}
  - name: press
    channels: {{p1: press_rig.p1, p2: press_rig.p2}}
    detector: {{kind: default, options: {{settle_seconds: 2, learn_seconds: 12}}}}
events: {{log: events.jsonl}}
metrics: {{port: {port}, trend_interval_s: 0.5}}
state: {{directory: ""}}
worker: {{priority: 0}}
realtime: {{cpu_wakeup_latency_us: -1}}
"""


def alarm_metric(metrics, state):
    # alarm_state is the alarm's ISA-18.2 state; `state` repeats it for one release.
    prefix = (f'leakmon_alarm_active{{actuator="cylinder",alarm="internal_leakage",'
              f'alarm_state="{state}",state="{state}"}}')
    return any(line.startswith(prefix + " 1") for line in metrics.splitlines())


def console_errors(driver):
    return [entry for entry in driver.get_log("browser") if entry["level"] == "SEVERE"]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--leakmon", required=True)
    parser.add_argument("--workdir", required=True)
    parser.add_argument("--screenshot")
    args = parser.parse_args()

    os.makedirs(args.workdir, exist_ok=True)
    port = free_port()
    config = os.path.join(args.workdir, "leakmon.yaml")
    friction_scenario = os.path.join(args.workdir, "press.yaml")
    with open(friction_scenario, "w") as f:
        f.write(FRICTION_SCENARIO)
    with open(config, "w") as f:
        f.write(CONFIG.format(onset=LEAK_ONSET_S, port=port, friction_scenario=friction_scenario))
    events = os.path.join(args.workdir, "events.jsonl")
    if os.path.exists(events):
        os.remove(events)
    base = f"http://127.0.0.1:{port}/"
    log = open(os.path.join(args.workdir, "daemon.log"), "w")
    daemon = subprocess.Popen([args.leakmon, "run", "--config", config], stdout=log, stderr=log)
    driver = None
    try:
        wait_for("the daemon's endpoint", lambda: http_text(base + "metrics"), 15)
        started = time.monotonic()

        driver = headless_chromium("1400,1500")
        driver.get(base)

        card = wait_for("the actuator's card",
                        lambda: driver.find_element(By.ID, "actuator-cylinder"), 15)
        first = wait_for("a first trend point", lambda: int(card.get_attribute("data-points")), 10)
        later = wait_for("the trend to advance",
                         lambda: (n := int(card.get_attribute("data-points"))) > first + 2 and n, 10)
        print(f"trend advanced from {first} to {later} points")
        assert driver.find_elements(By.CSS_SELECTOR, "#actuator-cylinder canvas"), "no chart drawn"
        errors = console_errors(driver)
        assert not errors, f"console errors after loading: {errors}"

        # Everything the page loaded came from the daemon (it must work offline).
        resources = driver.execute_script(
            "return performance.getEntriesByType('resource').map(e => e.name)")
        foreign = [r for r in resources if not r.startswith(base)]
        assert not foreign, f"resources from elsewhere: {foreign}"
        assert any(r.endswith("uplot.min.js") for r in resources), resources

        wait_for("the leak alarm on the page",
                 lambda: card.get_attribute("data-alarm-state") == "active_unacknowledged",
                 LEAK_ONSET_S + 30 - (time.monotonic() - started))
        print(f"alarm shown {time.monotonic() - started:.1f} s after the daemon started")
        assert alarm_metric(http_text(base + "metrics"), "active_unacknowledged")
        wait_for("the alarm event in the page's event list",
                 lambda: driver.find_elements(By.CSS_SELECTOR, "#events tr.alarm_raised"), 10)
        leak = card.find_element(By.CSS_SELECTOR, ".leak").text
        assert "±" in leak, f"leak size without its interval: {leak!r}"
        press = driver.find_element(By.ID, "actuator-press")
        # The press decides it is blind from its learning period's index windows; on a loaded
        # machine the loop's missed cycles are gaps that void windows, and learning takes longer.
        wait_for("the blind badge of the friction-held, pressure-only actuator",
                 lambda: press.find_element(By.CSS_SELECTOR, ".badge.blind").is_displayed(), 45)
        assert not card.find_element(By.CSS_SELECTOR, ".badge.blind").is_displayed(), \
            "the flow-balance actuator is shown blind"
        with open(events) as f:
            assert '"event": "detection_blind", "actuator": "press"' in f.read(), \
                "no detection_blind event for the press"
        # Let the charts draw the alarm's surroundings before the picture.
        wait_for("two more trend points",
                 lambda: int(card.get_attribute("data-points")) > later + 6, 10)
        if args.screenshot:
            os.makedirs(os.path.dirname(os.path.abspath(args.screenshot)), exist_ok=True)
            height = driver.execute_script("return document.body.scrollHeight")
            driver.set_window_size(1400, min(max(height + 40, 900), 2400))
            time.sleep(1.5)
            driver.save_screenshot(args.screenshot)
            print(f"screenshot: {args.screenshot}")

        button = card.find_element(By.CSS_SELECTOR, "button.ack")
        assert button.is_enabled()
        button.click()
        wait_for("the daemon to record the acknowledgement",
                 lambda: alarm_metric(http_text(base + "metrics"), "active_acknowledged"), 10)
        wait_for("the page to show it",
                 lambda: card.get_attribute("data-alarm-state") == "active_acknowledged", 10)
        with open(events) as f:
            assert '"event": "alarm_acknowledged"' in f.read(), "no alarm_acknowledged event"

        errors = console_errors(driver)
        assert not errors, f"console errors: {errors}"
        print(f"live page test passed in {time.monotonic() - started:.1f} s")
        return 0
    finally:
        if driver is not None:
            driver.quit()
        daemon.send_signal(signal.SIGTERM)
        try:
            daemon.wait(timeout=10)
        except subprocess.TimeoutExpired:
            daemon.kill()
        log.close()


if __name__ == "__main__":
    sys.exit(main())
