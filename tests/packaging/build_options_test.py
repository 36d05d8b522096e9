#!/usr/bin/python3
"""The build switches of docs/developing.md, on fresh configurations of the source tree.

README's first command (`cmake -S . -B build -G Ninja && cmake --build build`) must build the
binary and nothing else: no test, no benchmark, and no -Werror (a user's or packager's build
must not fail on a newer compiler's new warning). BUILD_TESTING=ON (CTest's switch) brings the
tests and -Werror; LEAKMON_BUILD_TESTS, its former name, still works; LEAKMON_WERROR overrides.
The installed unit and `leakmon status`/`ack` must agree on the configuration's path for any
prefix; the default prefix is /usr (the package's).

    build_options_test.py SOURCE_DIR SCRATCH_DIR
"""
import json
import pathlib
import re
import shutil
import subprocess
import sys

SOURCE = pathlib.Path(sys.argv[1])
SCRATCH = pathlib.Path(sys.argv[2])
failures = []


def check(condition, message):
    print(("ok   " if condition else "FAIL ") + message)
    if not condition:
        failures.append(message)


def configure(name, *options):
    build = SCRATCH / name
    shutil.rmtree(build, ignore_errors=True)
    result = subprocess.run(["cmake", "-S", str(SOURCE), "-B", str(build), "-G", "Ninja",
                             *options], capture_output=True, text=True)
    if result.returncode != 0:
        print(result.stdout, result.stderr)
        raise SystemExit(f"configuring {name} failed")
    return build


def targets(build):
    out = subprocess.run(["ninja", "-C", str(build), "-t", "targets", "all"],
                         capture_output=True, text=True, check=True).stdout
    return {line.split(":")[0] for line in out.splitlines()}


def executables(build):
    return {t[len("bin/"):] for t in targets(build) if t.startswith("bin/")}


def compile_flags(build, source_suffix):
    for entry in json.loads((build / "compile_commands.json").read_text()):
        if entry["file"].endswith(source_suffix):
            return entry["command"]
    raise SystemExit(f"no compile command for {source_suffix}")


def cache(build, name):
    match = re.search(rf"^{name}:[A-Z]+=(.*)$", (build / "CMakeCache.txt").read_text(), re.M)
    return match.group(1) if match else None


def unit_config(build):
    unit = (build / "systemd" / "leakmon.service").read_text()
    return re.search(r"^ExecStart=\S+ run --config (\S+)$", unit, re.M).group(1)


# README's first command: the binary only, warnings not errors, installed under /usr.
default = configure("default")
built = executables(default)
check(built == {"leakmon"}, f"the default build makes bin/leakmon only (got {sorted(built)})")
check("-Werror" not in compile_flags(default, "cli/main.cpp"),
      "the default build does not turn warnings into errors")
check(cache(default, "CMAKE_INSTALL_PREFIX") == "/usr", "the default prefix is /usr")
check(unit_config(default) == "/etc/leakmon/leakmon.yaml",
      f"the unit reads /etc/leakmon/leakmon.yaml (got {unit_config(default)})")
check('LEAKMON_DEFAULT_CONFIG=\\"/etc/leakmon/leakmon.yaml\\"'
      in compile_flags(default, "cli/status_command.cpp"),
      "status and ack look for /etc/leakmon/leakmon.yaml")

# The development and CI build: tests and -Werror.
testing = configure("testing", "-DBUILD_TESTING=ON")
built = executables(testing)
check("leakmon" in built and "capture_test" in built and len(built) > 50,
      f"BUILD_TESTING=ON builds the tests ({len(built)} executables)")
check(not any(name.endswith("_bench") for name in built), "the benchmarks stay out by default")
check("-Werror" in compile_flags(testing, "cli/main.cpp"), "BUILD_TESTING=ON: -Werror")
off = configure("testing_off", "-DBUILD_TESTING=OFF", "-DLEAKMON_BUILD_BENCH=ON")
built = executables(off)
check(not any(name.endswith("_test") for name in built) and "sim_bench" in built,
      "BUILD_TESTING=OFF with LEAKMON_BUILD_BENCH=ON: benchmarks, no tests")

# The former name, and the explicit override.
legacy = configure("legacy", "-DLEAKMON_BUILD_TESTS=ON", "-DLEAKMON_WERROR=OFF")
check(cache(legacy, "BUILD_TESTING") == "ON", "LEAKMON_BUILD_TESTS=ON sets BUILD_TESTING")
check("capture_test" in executables(legacy), "... and the tests are built")
check("-Werror" not in compile_flags(legacy, "cli/main.cpp"), "LEAKMON_WERROR=OFF wins")

# Another prefix: unit and binary still agree.
local = configure("local", "-DCMAKE_INSTALL_PREFIX=/usr/local")
check(unit_config(local) == "/usr/local/etc/leakmon/leakmon.yaml",
      f"prefix /usr/local: the unit reads {unit_config(local)}")
check('LEAKMON_DEFAULT_CONFIG=\\"/usr/local/etc/leakmon/leakmon.yaml\\"'
      in compile_flags(local, "cli/status_command.cpp"),
      "prefix /usr/local: status and ack look where the unit looks")

for name in ("default", "testing", "testing_off", "legacy", "local"):
    shutil.rmtree(SCRATCH / name, ignore_errors=True)
print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
