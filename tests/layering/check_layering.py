#!/usr/bin/python3
"""The house's layering rule: a library folder includes only folders before it in

    config, capture, dsp, sim, io, detect, model, daemon, study, cli

(tests/, bench/ and fuzz/ may include anything). Reads every `#include "folder/..."` in the
library folders and prints each violation as `file:line: ...`; exit status 1 when there is
one. Folders of the order that do not exist (yet) are skipped.

    check_layering.py ROOT        check the tree at ROOT
    check_layering.py --self-test check a scratch tree with a known bad include (and good ones)
"""

import pathlib
import re
import sys
import tempfile

ORDER = ["config", "capture", "dsp", "sim", "io", "detect", "model", "daemon", "study", "cli"]
SOURCE_SUFFIXES = {".hpp", ".cpp", ".h", ".cc", ".hh", ".cxx", ".ipp", ".inl"}
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"/]+)/[^"]*"')


def violations(root):
    """(file, line, message) for every include of a later folder, in path order."""
    root = pathlib.Path(root)
    rank = {folder: i for i, folder in enumerate(ORDER)}
    found = []
    for folder in ORDER:
        base = root / folder
        if not base.is_dir():
            continue
        for path in sorted(base.rglob("*")):
            if path.suffix not in SOURCE_SUFFIXES or not path.is_file():
                continue
            text = path.read_text(encoding="utf-8", errors="replace")
            for number, line in enumerate(text.splitlines(), start=1):
                match = INCLUDE.match(line)
                if not match:
                    continue
                target = match.group(1)
                if target in rank and rank[target] > rank[folder]:
                    found.append((path.relative_to(root).as_posix(), number,
                                  f"{folder}/ includes {target}/ ({line.strip()}), but {target} "
                                  f"comes after {folder} in {', '.join(ORDER)}"))
    return found


def report(found):
    for file, line, message in found:
        print(f"{file}:{line}: {message}")
    return 1 if found else 0


def self_test():
    """The checker must name a bad include by file and line, and pass good trees."""
    failures = []
    with tempfile.TemporaryDirectory() as scratch:
        root = pathlib.Path(scratch)

        def write(relative, text):
            path = root / relative
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")

        # A good tree without study/ and cli/ (they may not exist yet).
        write("config/a.hpp", "#pragma once\n#include <string>\n")
        write("dsp/b.hpp", '#pragma once\n#include "config/a.hpp"\n#include "dsp/c.hpp"\n')
        write("daemon/sub/d.cpp", '#include "io/driver.hpp"\n#include "capture/capture.hpp"\n')
        write("tests/daemon/t.cpp", '#include "cli/anything.hpp"\n')  # tests are exempt
        write("detect/e.cpp", '// #include "daemon/x.hpp" in a comment is no include\n')
        if violations(root):
            failures.append(f"good tree reported: {violations(root)}")

        # The deliberately bad examples: detect/ including daemon/, io/ including daemon/ in a
        # subfolder, and a library including the later cli/.
        write("detect/bad.hpp", '#pragma once\n\n#include "dsp/b.hpp"\n#include "daemon/event.hpp"\n')
        write("io/modbus/out.hpp", '#pragma once\n  #  include "daemon/event.hpp"\n')
        write("study/s.cpp", '#include "cli/args.hpp"\n')
        found = violations(root)
        expected = {("detect/bad.hpp", 4), ("io/modbus/out.hpp", 2), ("study/s.cpp", 1)}
        got = {(file, line) for file, line, _ in found}
        if got != expected:
            failures.append(f"bad tree: expected {sorted(expected)}, got {sorted(got)}")
        printed = [f"{file}:{line}:" for file, line, _ in found]
        if "detect/bad.hpp:4:" not in printed:
            failures.append("the violation does not name detect/bad.hpp:4")
        if report(found) != 1:
            failures.append("a bad tree does not give exit status 1")
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
        print(f"layering: ok ({', '.join(f for f in ORDER if (pathlib.Path(argv[1]) / f).is_dir())})")
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv))
