#!/usr/bin/python3
"""A real Modbus peer for leakmon's tests and benchmarks: Debian's pymodbus server serving
registers that follow a capture, with faults that can be switched on at run time.

  modbus_server.py --ready-file F (--tcp-port N | --serial DEVICE [--baud B --parity P])
                   [--capture CSV --map SPEC --rate HZ [--epoch T]] [--unit ID] [--slow-seconds S]
                   [--garbage]

SPEC is a comma-separated list of name:register:address:type:order:scale:offset. `name` is a
capture column, or `index...` (any name starting so) for the number of the sample being served
(the test uses it to know which capture row a read saw); the row served is the one due at the
wall-clock time of the answer, counted from --epoch (default: the server's start). `register` is
holding, input, coil or discrete_input; `address` is the protocol (0-based) address; type INT16
UINT16 INT32 UINT32 FLOAT32 FLOAT64; order ABCD CDAB BADC DCBA; the served raw value is
(value - offset) / scale, rounded for integer types.
The encoding is written independently of leakmon's decoders (Python's struct), so the test is
a check of one against the other.

The ready file receives the TCP port once the server listens (port 0 picks a free one).
SIGUSR1 toggles slow mode (each request waits --slow-seconds before it is answered);
SIGUSR2 toggles exception mode (every request is refused with ILLEGAL DATA ADDRESS).
--garbage serves no Modbus at all: every request is answered with random bytes.
"""
import argparse
import asyncio
import logging
import os
import random
import signal
import struct
import time

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.framer.rtu_framer import ModbusRtuFramer
from pymodbus.framer.socket_framer import ModbusSocketFramer
from pymodbus.server.async_io import ModbusSerialServer, ModbusTcpServer

STORE_SIZE = 4096
STRUCT = {"INT16": ">h", "UINT16": ">H", "INT32": ">i", "UINT32": ">I", "FLOAT32": ">f",
          "FLOAT64": ">d"}
FUNCTION = {"coil": 1, "discrete_input": 2, "holding": 3, "input": 4}


def encode(value, data_type, order):
    """Registers as the device sends them, for a value in big-endian (ABCD) byte order."""
    if data_type.startswith("FLOAT"):
        raw = struct.pack(STRUCT[data_type], value)
    else:
        raw = struct.pack(STRUCT[data_type], int(round(value)))
    words = [raw[i:i + 2] for i in range(0, len(raw), 2)]
    if order in ("BADC", "DCBA"):
        words = [w[::-1] for w in words]
    if order in ("CDAB", "DCBA"):
        words = words[::-1]
    return [int.from_bytes(w, "big") for w in words]


def read_capture(path):
    columns, rows = None, []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            if columns is None:
                columns = line.split(",")
                continue
            rows.append([float(x) if x not in ("", "nan") else float("nan")
                         for x in line.split(",")])
    return columns, rows


class FaultySlaveContext(ModbusSlaveContext):
    """A slave whose answers can be delayed or refused while the server runs."""

    def __init__(self, slow_seconds, **kwargs):
        super().__init__(**kwargs)
        self.slow = False
        self.refuse = False
        self.slow_seconds = slow_seconds
        self.requests = 0
        self.before_answer = None

    def validate(self, fc_as_hex, address, count=1):
        self.requests += 1
        if self.slow:
            time.sleep(self.slow_seconds)  # blocks the whole server, as a stalled device would
        if self.refuse:
            return False
        if self.before_answer:
            self.before_answer()
        return super().validate(fc_as_hex, address, count)


def make_context(args):
    slave = FaultySlaveContext(
        args.slow_seconds, zero_mode=True,
        di=ModbusSequentialDataBlock(0, [0] * STORE_SIZE),
        co=ModbusSequentialDataBlock(0, [0] * STORE_SIZE),
        hr=ModbusSequentialDataBlock(0, [0] * STORE_SIZE),
        ir=ModbusSequentialDataBlock(0, [0] * STORE_SIZE))
    return slave, ModbusServerContext(slaves={args.unit: slave}, single=False)


def parse_map(spec):
    entries = []
    for item in filter(None, spec.split(",")):
        name, register, address, data_type, order, scale, offset = item.split(":")
        entries.append((name, FUNCTION[register], int(address), data_type, order, float(scale),
                        float(offset)))
    return entries


class CaptureFollower:
    """Serves row `index % rows` of the capture, the next row every 1/rate seconds."""

    def __init__(self, slave, args):
        self.slave = slave
        self.columns, self.rows = read_capture(args.capture)
        self.entries = parse_map(args.map)
        self.period = 1.0 / args.rate
        self.epoch = args.epoch if args.epoch is not None else time.time()
        self.served = -1

    def serve(self, index):
        # No await in here: a request never sees half a row.
        row = self.rows[index % len(self.rows)]
        for name, function, address, data_type, order, scale, offset in self.entries:
            value = index if name.startswith("index") else row[self.columns.index(name)]
            raw = (value - offset) / scale
            if function in (1, 2):
                self.slave.setValues(function, address, [bool(round(raw))])
            else:
                self.slave.setValues(function, address, encode(raw, data_type, order))

    def serve_now(self):
        # The row is picked when a request is answered, from the wall clock since `epoch`, as a
        # device samples a process that goes on while its server is down or starved of CPU: a
        # restarted server continues where the process is, and a late answer carries the newest
        # row, never a stale one or a burst of them.
        index = max(0, int((time.time() - self.epoch) / self.period))
        if index != self.served:
            self.serve(index)
            self.served = index


async def serve_garbage(args):
    rng = random.Random(1234)

    async def answer(reader, writer):
        while data := await reader.read(260):
            writer.write(bytes(rng.randrange(256) for _ in range(len(data) + rng.randrange(8))))
            await writer.drain()

    server = await asyncio.start_server(answer, "127.0.0.1", args.tcp_port, reuse_address=True)
    write_ready(args.ready_file, server.sockets[0].getsockname()[1])
    await server.serve_forever()


def write_ready(path, port):
    with open(path + ".tmp", "w") as f:
        f.write(f"{port}\n")
    os.replace(path + ".tmp", path)


async def main(args):
    if args.garbage:
        await serve_garbage(args)
        return
    slave, context = make_context(args)
    loop = asyncio.get_running_loop()
    loop.add_signal_handler(signal.SIGUSR1, lambda: setattr(slave, "slow", not slave.slow))
    loop.add_signal_handler(signal.SIGUSR2, lambda: setattr(slave, "refuse", not slave.refuse))
    if args.capture:
        follower = CaptureFollower(slave, args)
        follower.serve_now()
        slave.before_answer = follower.serve_now
    if args.serial:
        server = ModbusSerialServer(context, framer=ModbusRtuFramer, port=args.serial,
                                    baudrate=args.baud, parity=args.parity, bytesize=8,
                                    stopbits=1, timeout=0.005)
        await server.start()
        write_ready(args.ready_file, 0)
        await server.serve_forever()
    else:
        server = ModbusTcpServer(context, framer=ModbusSocketFramer,
                                 address=("127.0.0.1", args.tcp_port), allow_reuse_address=True)
        task = asyncio.create_task(server.serve_forever())
        await server.serving
        write_ready(args.ready_file, server.server.sockets[0].getsockname()[1])
        await task


if __name__ == "__main__":
    logging.disable(logging.CRITICAL)  # pymodbus logs every exception reply it sends
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--ready-file", required=True)
    parser.add_argument("--tcp-port", type=int, default=0)
    parser.add_argument("--serial")
    parser.add_argument("--baud", type=int, default=19200)
    parser.add_argument("--parity", default="E")
    parser.add_argument("--unit", type=int, default=1)
    parser.add_argument("--capture")
    parser.add_argument("--map", default="")
    parser.add_argument("--rate", type=float, default=500.0)
    parser.add_argument("--epoch", type=float,
                        help="wall-clock time (s since 1970) of row 0; default: the server's start")
    parser.add_argument("--slow-seconds", type=float, default=0.2)
    parser.add_argument("--garbage", action="store_true")
    asyncio.run(main(parser.parse_args()))
