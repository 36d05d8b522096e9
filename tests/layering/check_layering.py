#!/usr/bin/python3
"""The house's layering rules, over every `#include "room/..."` in the library rooms:

1. A room includes only rooms before it in

       config, capture, dsp, sim, io, detect, model,
       realtime, pipeline, study, http, views, daemon, cli

   (tests/, bench/ and fuzz/ may include anything). realtime/ is the acquisition loop and
   its ring, pipeline/ the worker side (also replay), study/ what is built on the pipeline
   alone, http/ the transport, views/ the formatting of the service's snapshot, daemon/ the
   service that owns them all.

2. No room has an include loop inside it. A component is a header with its source (x.hpp and
   x.cpp); component A uses B when a file of A includes a file of B. A loop (A uses B uses A,
   or longer) makes the two one unit in all but name: neither can be read, tested or moved
   without the other. A source including its own header is no loop.

Prints each violation as `file:line: ...` and exits with status 1 when there is one. Rooms of
the order that do not exist are skipped.

    check_layering.py ROOT        check the tree at ROOT
    check_layering.py --self-test check scratch trees with known violations (and good ones)
"""

import io
import pathlib
import re
import sys
import tempfile

ORDER = ["config", "capture", "dsp", "sim", "io", "detect", "model",
         "realtime", "pipeline", "study", "http", "views", "daemon", "cli"]
SOURCE_SUFFIXES = {".hpp", ".cpp", ".h", ".cc", ".hh", ".cxx", ".ipp", ".inl"}
INCLUDE = re.compile(r'^\s*#\s*include\s*"(([^"/]+)/[^"]*)"')


def sources(root):
    """(room, path) of every source file of the rooms, in path order."""
    for room in ORDER:
        base = root / room
        if not base.is_dir():
            continue
        for path in sorted(base.rglob("*")):
            if path.suffix in SOURCE_SUFFIXES and path.is_file():
                yield room, path


def includes(path):
    """(line number, included path, its first folder, line text) of each quoted include."""
    text = path.read_text(encoding="utf-8", errors="replace")
    for number, line in enumerate(text.splitlines(), start=1):
        match = INCLUDE.match(line)
        if match:
            yield number, match.group(1), match.group(2), line.strip()


def order_violations(root):
    """(file, line, message) for every include of a later room."""
    rank = {room: i for i, room in enumerate(ORDER)}
    found = []
    for room, path in sources(root):
        for number, _, target, line in includes(path):
            if target in rank and rank[target] > rank[room]:
                found.append((path.relative_to(root).as_posix(), number,
                              f"{room}/ includes {target}/ ({line}), but {target} comes after "
                              f"{room} in {', '.join(ORDER)}"))
    return found


def component(relative):
    """The component of a repository-relative file: its path without the suffix."""
    return str(pathlib.PurePosixPath(relative).with_suffix(""))


def loop_violations(root):
    """(file, line, message) for every include loop between components of one room: one
    entry per loop, at the first include of its shortest cycle."""
    # uses[a][b] = (file, line) of the first include by which component a uses b.
    uses = {}
    room_of = {}
    for room, path in sources(root):
        relative = path.relative_to(root).as_posix()
        here = component(relative)
        room_of[here] = room
        edges = uses.setdefault(here, {})
        for number, included, target, _ in includes(path):
            there = component(included)
            if target != room or there == here:
                continue
            edges.setdefault(there, (relative, number))
    for edges in uses.values():
        for there in list(edges):
            if there not in room_of:
                del edges[there]  # an include of a file that does not exist: the compiler's

    # Strongly connected components (Tarjan, iterative): each with more than one component,
    # or one that uses itself, is a loop.
    index, low, on_stack, stack, groups = {}, {}, set(), [], []
    counter = 0
    for start in sorted(uses):
        if start in index:
            continue
        work = [(start, iter(sorted(uses[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            advanced = False
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(uses.get(child, {})))))
                    advanced = True
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            if advanced:
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                group = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    group.append(member)
                    if member == node:
                        break
                if len(group) > 1:
                    groups.append(sorted(group))

    found = []
    for group in groups:
        cycle = shortest_cycle(uses, group)
        steps = []
        for a, b in zip(cycle, cycle[1:] + cycle[:1]):
            file, line = uses[a][b]
            steps.append(f"{file}:{line} includes {b}")
        file, line = uses[cycle[0]][cycle[1]]
        found.append((file, line,
                      f"include loop inside {room_of[cycle[0]]}/: " + "; ".join(steps) +
                      f" (components {' -> '.join(cycle + cycle[:1])})"))
    return sorted(found)


def shortest_cycle(uses, group):
    """The shortest cycle through the group's first member, as a list of components."""
    members = set(group)
    start = group[0]
    previous = {start: None}
    frontier = [start]
    while frontier:
        following = []
        for node in frontier:
            for child in sorted(uses.get(node, {})):
                if child not in members:
                    continue
                if child == start:
                    path = [node]
                    while previous[path[-1]] is not None:
                        path.append(previous[path[-1]])
                    return list(reversed(path))
                if child not in previous:
                    previous[child] = node
                    following.append(child)
        frontier = following
    return group  # unreachable for a strongly connected group


def violations(root):
    root = pathlib.Path(root)
    return order_violations(root) + loop_violations(root)


def report(found, out=None):
    for file, line, message in found:
        print(f"{file}:{line}: {message}", file=out or sys.stdout)
    return 1 if found else 0


def self_test():
    """The checker names bad includes and loops by file and line, and passes good trees."""
    failures = []

    def tree(files):
        scratch = tempfile.TemporaryDirectory()
        root = pathlib.Path(scratch.name)
        for relative, text in files.items():
            path = root / relative
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
        return scratch, root

    def expect(name, files, expected, *, words=()):
        scratch, root = tree(files)
        with scratch:
            found = violations(root)
            got = {(file, line) for file, line, _ in found}
            if got != expected:
                failures.append(f"{name}: expected {sorted(expected)}, got {sorted(got)} "
                                f"({found})")
            for word in words:
                if not any(word in message for _, _, message in found):
                    failures.append(f"{name}: no message says '{word}': {found}")
            if expected and report(found, io.StringIO()) != 1:
                failures.append(f"{name}: a bad tree does not give exit status 1")

    good = {
        "config/a.hpp": "#pragma once\n#include <string>\n",
        "dsp/b.hpp": '#pragma once\n#include "config/a.hpp"\n#include "dsp/c.hpp"\n',
        "dsp/c.hpp": "#pragma once\n",
        "realtime/ring.hpp": '#pragma once\n#include "io/driver.hpp"\n',
        "pipeline/worker.hpp": '#pragma once\n#include "realtime/ring.hpp"\n',
        "pipeline/worker.cpp": '#include "pipeline/worker.hpp"\n#include "pipeline/alarm.hpp"\n',
        "pipeline/alarm.hpp": "#pragma once\n",
        "study/run.cpp": '#include "pipeline/worker.hpp"\n',
        "http/endpoint.hpp": "#pragma once\n",
        "views/page.hpp": '#pragma once\n#include "http/endpoint.hpp"\n',
        "views/page.cpp": '#include "views/page.hpp"\n#include "pipeline/worker.hpp"\n',
        "daemon/daemon.hpp": '#pragma once\n#include "views/page.hpp"\n',
        "daemon/sub/d.cpp": '#include "io/driver.hpp"\n#include "capture/capture.hpp"\n',
        "tests/daemon/t.cpp": '#include "cli/anything.hpp"\n',  # tests are exempt
        "detect/e.cpp": '// #include "daemon/x.hpp" in a comment is no include\n',
    }
    expect("good tree", good, set())

    # Rule 1: detect/ including daemon/, io/ including daemon/ in a subfolder, a library
    # including the later cli/, a view including the service, the pipeline including a view,
    # and study/ including the transport.
    expect("order", {**good,
                     "detect/bad.hpp": '#pragma once\n\n#include "dsp/b.hpp"\n'
                                       '#include "daemon/event.hpp"\n',
                     "io/modbus/out.hpp": '#pragma once\n  #  include "daemon/event.hpp"\n',
                     "study/s.cpp": '#include "cli/args.hpp"\n',
                     "views/metrics.cpp": '#include "views/page.hpp"\n'
                                          '#include "daemon/daemon.hpp"\n',
                     "pipeline/replay.cpp": '#include "views/page.hpp"\n',
                     "study/t.cpp": '#include "pipeline/worker.hpp"\n#include "http/endpoint.hpp"\n'},
           {("detect/bad.hpp", 4), ("io/modbus/out.hpp", 2), ("study/s.cpp", 1),
            ("views/metrics.cpp", 2), ("pipeline/replay.cpp", 1), ("study/t.cpp", 2)},
           words=["comes after"])

    # Rule 2, two components: the source of one includes the other's header and the other's
    # source includes the first's header (the daemon and its page before the snapshot).
    expect("loop of two", {**good,
                           "daemon/view.hpp": "#pragma once\n",
                           "daemon/view.cpp": '#include "daemon/view.hpp"\n'
                                              '#include "daemon/service.hpp"\n',
                           "daemon/service.hpp": '#pragma once\n#include "daemon/view.hpp"\n'},
           {("daemon/service.hpp", 2)}, words=["include loop inside daemon/"])

    # Rule 2, headers only, three long: a -> b -> c -> a in a subfolder.
    expect("loop of three", {**good,
                             "io/mqtt/a.hpp": '#pragma once\n#include "io/mqtt/b.hpp"\n',
                             "io/mqtt/b.hpp": '#pragma once\n#include "io/mqtt/c.hpp"\n',
                             "io/mqtt/c.hpp": '#pragma once\n\n#include "io/mqtt/a.hpp"\n'},
           {("io/mqtt/a.hpp", 2)}, words=["io/mqtt/b", "io/mqtt/c", "include loop inside io/"])

    # Both rules at once, and a loop that is not the first pair in path order.
    expect("both", {**good,
                    "views/metrics.cpp": '#include "daemon/daemon.hpp"\n',
                    "pipeline/z.hpp": '#pragma once\n#include "pipeline/y.hpp"\n',
                    "pipeline/y.cpp": '#include "pipeline/z.hpp"\n'},
           {("views/metrics.cpp", 1), ("pipeline/y.cpp", 1)})

    # Not loops: a source including its own header, a chain, and includes across rooms in
    # order that come back to the room by another component.
    expect("no loop", {**good,
                       "pipeline/a.hpp": '#pragma once\n#include "pipeline/b.hpp"\n',
                       "pipeline/a.cpp": '#include "pipeline/a.hpp"\n#include "pipeline/b.hpp"\n',
                       "pipeline/b.hpp": '#pragma once\n#include "realtime/ring.hpp"\n'},
           set())

    for failure in failures:
        print(f"SELF-TEST FAILED: {failure}")
    print("self-test: ok" if not failures else "self-test: failed")
    return 1 if failures else 0


def main(argv):
    if len(argv) == 2 and argv[1] == "--self-test":
        return self_test()
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    found = violations(argv[1])
    status = report(found)
    if status == 0:
        rooms = [f for f in ORDER if (pathlib.Path(argv[1]) / f).is_dir()]
        print(f"layering: ok, no include loop ({', '.join(rooms)})")
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv))
