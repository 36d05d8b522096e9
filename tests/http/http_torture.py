#!/usr/bin/python3
"""HTTP torture of a running `leakmon run`: slow-drip clients, an idle-connection flood, a burst
of scrapes, oversized request lines and headers (5000 headers) and malformed queries, all at
once, while a probe scrapes /metrics every 100 ms.

Test mode (ctest http_torture) asserts that every probe is answered 200 within a generous
2 s, that the server closes dripping connections by its request deadline, that the oversized and
malformed requests get their 414/431/413/400 answers, that the acquisition loop's cycle count
keeps advancing (every probe sees more cycles, and fewer than 5 % of the periods are missed).

The loop's overruns are printed for a quiet control window (no HTTP load) just before and for the
torture window; --strict-overruns also fails when the torture window has any. That is not the
default: on the shared 2-core CI machine the loop overruns without any HTTP load at all (24, 1
and 0 overruns in three quiet 10 s windows, docs/performance.md), so a strict check would fail
on the machine's noise, not on the endpoint.

Bench mode (--bench SECONDS) runs the same load longer and prints the probe latency percentiles
(docs/performance.md); --hammer makes the burst clients scrape back to back without pauses, an
unbounded load (thousands of scrapes a second) beyond what the test asserts on.

usage: http_torture.py LEAKMON_BINARY SCRATCH_DIR [--bench SECONDS]
"""
import argparse
import os
import shutil
import socket
import subprocess
import sys
import threading
import time

DRIP_CLIENTS = 20
IDLE_CONNECTIONS = 300
BURST_CLIENTS = 4
BURST_REQUESTS = 25  # back to back per client, then a pause of BURST_PAUSE_S (--hammer: none)
BURST_PAUSE_S = 1.0
PROBE_BOUND_S = 2.0
CONTROL_S = 8.0
TORTURE_S = 15.0
DEADLINE_BOUND_S = 12.0  # request deadline 5 s + idle timeout + the watchdog's period, generously


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def connect(port, timeout=5.0):
    s = socket.create_connection(("127.0.0.1", port), timeout=timeout)
    s.settimeout(timeout)
    return s


def exchange(port, request, timeout=5.0):
    """Sends raw bytes; returns (status code or None, body bytes, seconds)."""
    start = time.monotonic()
    try:
        with connect(port, timeout) as s:
            try:
                s.sendall(request)
            except OSError:
                pass  # answered and closed before reading it all
            reply = b""
            while True:
                chunk = s.recv(65536)
                if not chunk:
                    break
                reply += chunk
    except OSError:
        return None, b"", time.monotonic() - start
    elapsed = time.monotonic() - start
    head, _, body = reply.partition(b"\r\n\r\n")
    parts = head.split(b" ", 2)
    code = int(parts[1]) if len(parts) > 1 and parts[1].isdigit() else None
    return code, body, elapsed


def get(port, path, timeout=5.0):
    return exchange(port, f"GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n".encode(), timeout)


def metric(text, name):
    for line in text.splitlines():
        if line.startswith(name + "{") or line.startswith(name + " "):
            return float(line.rsplit(" ", 1)[1])
    raise KeyError(name)


class Load:
    def __init__(self, port, hammer):
        self.port = port
        self.hammer = hammer
        self.stop = threading.Event()
        self.lock = threading.Lock()
        self.drip_lifetimes = []   # seconds from connect to the server's close
        self.wrong_answers = []    # (what, code) for oversized/malformed requests
        self.answered = {"oversized": 0, "malformed": 0, "burst": 0}
        self.idle = []
        self.threads = []

    def start(self):
        for _ in range(DRIP_CLIENTS):
            self.threads.append(threading.Thread(target=self.drip, daemon=True))
        for _ in range(BURST_CLIENTS):
            self.threads.append(threading.Thread(target=self.burst, daemon=True))
        self.threads.append(threading.Thread(target=self.oversized, daemon=True))
        self.threads.append(threading.Thread(target=self.malformed, daemon=True))
        self.threads.append(threading.Thread(target=self.flood, daemon=True))
        for t in self.threads:
            t.start()

    def finish(self):
        self.stop.set()
        for t in self.threads:
            t.join(timeout=10)
        for s in self.idle:
            s.close()

    def drip(self):
        request = b"GET /metrics HTTP/1.1\r\nHost: x\r\n\r\n"
        while not self.stop.is_set():
            try:
                s = connect(self.port)
            except OSError:
                time.sleep(0.2)
                continue
            start = time.monotonic()
            closed = False
            for byte in request:
                if self.stop.wait(1.0):
                    break
                try:
                    s.send(bytes([byte]))
                    s.setblocking(False)
                    if s.recv(1) == b"":
                        closed = True
                except BlockingIOError:
                    pass
                except OSError:
                    closed = True
                finally:
                    s.setblocking(True)
                if closed:
                    break
            if closed:
                with self.lock:
                    self.drip_lifetimes.append(time.monotonic() - start)
            s.close()

    def flood(self):
        """Keeps IDLE_CONNECTIONS connections open that never send a byte."""
        while not self.stop.is_set():
            alive = []
            for s in self.idle:
                try:
                    s.setblocking(False)
                    if s.recv(1) == b"":
                        s.close()
                        continue
                except BlockingIOError:
                    pass
                except OSError:
                    s.close()
                    continue
                alive.append(s)
            self.idle = alive
            while len(self.idle) < IDLE_CONNECTIONS and not self.stop.is_set():
                try:
                    self.idle.append(connect(self.port, timeout=2.0))
                except OSError:
                    break
            self.stop.wait(0.5)

    def expect(self, kind, what, request, codes):
        code, _, _ = exchange(self.port, request, timeout=10.0)
        with self.lock:
            self.answered[kind] += 1
            if code not in codes:
                self.wrong_answers.append((what, code))

    def oversized(self):
        long_line = b"GET /metrics?" + b"a" * 70000 + b" HTTP/1.1\r\nHost: x\r\n\r\n"
        many = b"GET /metrics HTTP/1.1\r\nHost: x\r\n" + b"".join(
            b"X-%d: y\r\n" % i for i in range(5000)) + b"\r\n"
        huge_header = b"GET /metrics HTTP/1.1\r\nHost: x\r\nX-Big: " + b"b" * 60000 + b"\r\n\r\n"
        body = b"POST /ack HTTP/1.1\r\nHost: x\r\nContent-Length: 10000000\r\n\r\n"
        while not self.stop.is_set():
            self.expect("oversized", "request line of 70000 bytes", long_line, {414})
            self.expect("oversized", "5000 headers", many, {431})
            self.expect("oversized", "one 60000-byte header", huge_header, {431})
            self.expect("oversized", "10 MB body announced", body, {413})
            self.stop.wait(0.2)

    def malformed(self):
        cases = [("POST", "/ack?%%%%", {400}), ("POST", "/ack?foo=bar", {400}),
                 ("POST", "/ack?actuator", {400}), ("POST", "/ack?actuator=", {400}),
                 ("POST", "/ack?actuator=a&actuator=b", {400}), ("GET", "/status?format=%zz", {400}),
                 ("GET", "/metrics%", {400}), ("POST", "/metrics", {405}), ("DELETE", "/status", {405}),
                 ("GET", "/%00", {400})]
        while not self.stop.is_set():
            for method, target, codes in cases:
                request = f"{method} {target} HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n".encode()
                self.expect("malformed", f"{method} {target}", request, codes)
            self.stop.wait(0.2)

    def burst(self):
        while not self.stop.is_set():
            for _ in range(BURST_REQUESTS):
                code, _, _ = get(self.port, "/metrics")
                with self.lock:
                    if code == 200:
                        self.answered["burst"] += 1
            if not self.hammer:
                self.stop.wait(BURST_PAUSE_S)


def percentile(values, q):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("binary")
    parser.add_argument("scratch")
    parser.add_argument("--bench", type=float, default=0.0,
                        help="load this many seconds and print latency percentiles")
    parser.add_argument("--strict-overruns", action="store_true",
                        help="fail when the loop overruns at all during the torture (SCHED_FIFO)")
    parser.add_argument("--hammer", action="store_true",
                        help="burst clients scrape back to back without pauses (unbounded load)")
    args = parser.parse_args()
    shutil.rmtree(args.scratch, ignore_errors=True)
    os.makedirs(args.scratch)
    port = free_port()
    config = os.path.join(args.scratch, "leakmon.yaml")
    with open(config, "w") as f:
        f.write(f"""drivers:
  - {{name: rig, type: sim, scenario: healthy, seed: 7}}
sampling:
  - {{name: main, period_ms: 2, drivers: [rig], priority: 80}}
actuators:
  - name: cylinder
    channels: {{p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x, xref: rig.xref}}
    detector: {{kind: default, options: {{settle_seconds: 1, learn_seconds: 5}}}}
metrics: {{port: {port}}}
state: {{directory: ""}}
""")
    log = open(os.path.join(args.scratch, "daemon.log"), "w")
    daemon = subprocess.Popen([args.binary, "run", "--config", config], stdout=log, stderr=log)
    failures = []
    try:
        deadline = time.monotonic() + 20
        while get(port, "/metrics", 1.0)[0] != 200:
            if time.monotonic() > deadline or daemon.poll() is not None:
                print(open(os.path.join(args.scratch, "daemon.log")).read())
                sys.exit("daemon did not come up")
            time.sleep(0.1)
        time.sleep(1.0)  # past start-up, whose first cycles may overrun
        quiet = get(port, "/metrics")[1].decode()
        time.sleep(CONTROL_S)  # the control window: the machine's own overruns, no HTTP load
        before = get(port, "/metrics")[1].decode()
        control_overruns = metric(before, "leakmon_loop_overruns_total") - metric(
            quiet, "leakmon_loop_overruns_total")
        cycles0 = metric(before, "leakmon_loop_cycles_total")
        overruns0 = metric(before, "leakmon_loop_overruns_total")
        missed0 = metric(before, "leakmon_loop_missed_cycles_total")
        realtime = metric(before, "leakmon_loop_realtime") == 1

        load = Load(port, args.hammer)
        load.start()
        duration = args.bench if args.bench > 0 else TORTURE_S
        latencies, slow, cycles = [], [], [cycles0]
        end = time.monotonic() + duration
        while time.monotonic() < end:
            code, body, elapsed = get(port, "/metrics", timeout=PROBE_BOUND_S + 3)
            latencies.append(elapsed)
            if code != 200 or elapsed > PROBE_BOUND_S:
                slow.append((code, round(elapsed, 3)))
            elif b"leakmon_loop_cycles_total" in body:
                cycles.append(metric(body.decode(), "leakmon_loop_cycles_total"))
            time.sleep(0.1)
        idle_held = len(load.idle)
        load.finish()
        after = get(port, "/metrics")[1].decode()
        overruns1 = metric(after, "leakmon_loop_overruns_total")
        missed1 = metric(after, "leakmon_loop_missed_cycles_total")
        cycles1 = metric(after, "leakmon_loop_cycles_total")
        closes = metric(after, "leakmon_http_deadline_closes_total")

        print(f"probes: {len(latencies)}, p50 {percentile(latencies, 0.5) * 1e3:.1f} ms, "
              f"p99 {percentile(latencies, 0.99) * 1e3:.1f} ms, max {max(latencies) * 1e3:.1f} ms")
        print(f"idle connections held at the end: {idle_held}; drip connections closed by the "
              f"server: {len(load.drip_lifetimes)}, longest {max(load.drip_lifetimes, default=0):.1f} s; "
              f"deadline closes: {closes:.0f}")
        print(f"answered: {load.answered}; loop cycles {cycles0:.0f} -> {cycles[-1]:.0f}, "
              f"overruns {overruns0:.0f} -> {overruns1:.0f}, missed cycles {missed0:.0f} -> {missed1:.0f} "
              f"({'SCHED_FIFO' if realtime else 'normal scheduling'}); overruns in the quiet "
              f"{CONTROL_S:.0f} s before: {control_overruns:.0f}")

        if slow:
            failures.append(f"{len(slow)} of {len(latencies)} /metrics probes failed or took over "
                            f"{PROBE_BOUND_S} s: {slow[:5]}")
        if load.wrong_answers:
            failures.append(f"wrong answers: {load.wrong_answers[:5]}")
        if load.answered["oversized"] == 0 or load.answered["malformed"] == 0:
            failures.append(f"oversized/malformed requests never completed: {load.answered}")
        if not load.drip_lifetimes:
            failures.append("no dripping connection was closed by the server")
        elif max(load.drip_lifetimes) > DEADLINE_BOUND_S:
            failures.append(f"a dripping connection lived {max(load.drip_lifetimes):.1f} s")
        if idle_held < IDLE_CONNECTIONS // 2:
            failures.append(f"only {idle_held} idle connections could be opened")
        if any(b <= a for a, b in zip(cycles, cycles[1:])) or len(cycles) < 10:
            failures.append(f"loop cycles did not keep advancing: {cycles[:10]}...")
        if missed1 - missed0 > 0.05 * (cycles1 - cycles0):
            failures.append(f"the loop missed {missed1 - missed0:.0f} periods in {cycles1 - cycles0:.0f} cycles")
        if args.strict_overruns and overruns1 != overruns0:
            failures.append(f"loop overruns moved under HTTP load: {overruns0} -> {overruns1}")
    finally:
        daemon.terminate()
        try:
            daemon.wait(timeout=20)
        except subprocess.TimeoutExpired:
            daemon.kill()
            failures.append("daemon did not stop on SIGTERM")
    if daemon.returncode not in (0, -15) and not failures:
        failures.append(f"daemon exit code {daemon.returncode}")
    for failure in failures:
        print("FAIL:", failure)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
