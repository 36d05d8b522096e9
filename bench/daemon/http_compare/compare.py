#!/usr/bin/python3
"""Compares the three Debian HTTP server libraries leakmon could use (docs/performance.md):
builds a minimal /metrics server on each and measures, per library,
  drip:  /metrics probes while 20 clients send a request one byte every 1.5 s
  idle:  /metrics probes while 300 connections are held open without sending anything
  burst: wrk -t2 -c50 -d5s throughput and its p99 latency
A probe is one GET /metrics on a new connection with a 2 s timeout.

usage: bench/daemon/http_compare/compare.py [OUT_DIR=/tmp/http_compare]
"""
import os
import socket
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = sys.argv[1] if len(sys.argv) > 1 else "/tmp/http_compare"
SERVERS = {
    "libmicrohttpd 0.9.75": ("microhttpd_server.cpp", ["-lmicrohttpd"]),
    "civetweb 1.15": ("civetweb_server.cpp", ["-lcivetweb"]),
    "cpp-httplib 0.11.4": ("httplib_server.cpp", ["-lcpp-httplib", "-lpthread"]),
}


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def probe(port):
    start = time.monotonic()
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=2) as s:
            s.settimeout(2)
            s.sendall(b"GET /metrics HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
            data = b""
            while True:
                chunk = s.recv(65536)
                if not chunk:
                    break
                data += chunk
            ok = data.startswith(b"HTTP/1.1 200")
    except OSError:
        ok = False
    return ok, time.monotonic() - start


def probes(port, n=10):
    results = [probe(port) for _ in range(n) if not time.sleep(0.2)]
    good = [t for ok, t in results if ok]
    worst = max(t for _, t in results)
    return f"{len(good)}/{n} answered, worst {worst * 1e3:.0f} ms"


def drip(port, stop):
    while not stop.is_set():
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=2)
            for byte in b"GET /metrics HTTP/1.1\r\nHost: x\r\n\r\n":
                if stop.wait(1.5):
                    break
                s.send(bytes([byte]))
        except OSError:
            pass
        finally:
            s.close()


def main():
    os.makedirs(OUT, exist_ok=True)
    for name, (source, libs) in SERVERS.items():
        binary = os.path.join(OUT, source.replace(".cpp", ""))
        subprocess.run(["g++", "-std=c++20", "-O2", os.path.join(HERE, source), "-o", binary] + libs,
                       check=True)
        port = free_port()
        server = subprocess.Popen([binary, str(port)])
        time.sleep(0.5)
        try:
            row = [name, probes(port, 5)]
            stop = threading.Event()
            drips = [threading.Thread(target=drip, args=(port, stop), daemon=True) for _ in range(20)]
            for t in drips:
                t.start()
            time.sleep(2)
            row.append(probes(port))
            stop.set()
            for t in drips:
                t.join()
            idle = []
            for _ in range(300):
                try:
                    idle.append(socket.create_connection(("127.0.0.1", port), timeout=1))
                except OSError:
                    break
            row.append(f"{len(idle)} open; " + probes(port))
            for s in idle:
                s.close()
            time.sleep(0.5)
            wrk = subprocess.run(["wrk", "-t2", "-c50", "-d5s", "--latency", f"http://127.0.0.1:{port}/metrics"],
                                 capture_output=True, text=True).stdout
            rate = next((l.split()[1] for l in wrk.splitlines() if l.startswith("Requests/sec")), "?")
            p99 = next((l.split()[1] for l in wrk.splitlines() if l.strip().startswith("99%")), "?")
            row.append(f"{rate} req/s, p99 {p99}")
            print(" | ".join(row), flush=True)
        finally:
            server.kill()
            server.wait()


if __name__ == "__main__":
    main()
