#!/usr/bin/python3
"""`cpack -G DEB` of the build tree (FORMATS.md "Build output"), inspected without installing
it (scripts/check-package.sh installs, verifies and purges it in CI, as root).

The package must hold the stripped binary in /usr/bin, the unit reading
/etc/leakmon/leakmon.yaml, that file as a conffile holding a commented template for a real rig
(a field driver, the event log and learned state under /var/lib/leakmon; not the demo with its
simulated leak), the Prometheus rules, the man page (from --help, with every subcommand),
bash completion and the event log's rotation (also a conffile); its dependencies are the
shared libraries the binary links, nothing a test needs.

    deb_package_test.py BUILD_DIR SCRATCH_DIR
"""
import glob
import gzip
import os
import pathlib
import re
import shutil
import subprocess
import sys

BUILD = pathlib.Path(sys.argv[1])
SCRATCH = pathlib.Path(sys.argv[2])
failures = []


def check(condition, message):
    print(("ok   " if condition else "FAIL ") + message)
    if not condition:
        failures.append(message)


def run(*command, **kwargs):
    return subprocess.run(list(map(str, command)), capture_output=True, text=True, **kwargs)


prefix = re.search(r"^CMAKE_INSTALL_PREFIX:PATH=(.*)$",
                   (BUILD / "CMakeCache.txt").read_text(), re.M).group(1)
if prefix != "/usr":
    # A build tree configured before the default prefix became /usr keeps its cached one.
    print(f"FAIL this build tree installs under {prefix}, the package's paths are /usr and /etc: "
          f"configure a fresh build directory (the default prefix is /usr) or pass "
          f"-DCMAKE_INSTALL_PREFIX=/usr")
    sys.exit(1)
shutil.rmtree(SCRATCH, ignore_errors=True)
SCRATCH.mkdir(parents=True)
packed = run("cpack", "-G", "DEB", "--config", BUILD / "CPackConfig.cmake", "-B", SCRATCH)
print(packed.stdout[-2000:], packed.stderr[-2000:])
debs = glob.glob(str(SCRATCH / "leakmon_*.deb"))
check(packed.returncode == 0 and len(debs) == 1, f"cpack -G DEB wrote one leakmon_*.deb ({debs})")
if not debs:
    sys.exit(1)
deb = debs[0]
check(re.search(r"leakmon_\d+\.\d+\.\d+_amd64\.deb$", deb) is not None,
      f"Debian's file name leakmon_VERSION_ARCH.deb ({os.path.basename(deb)})")

fields = {name: run("dpkg-deb", "-f", deb, name).stdout.strip()
          for name in ("Package", "Version", "Depends", "Recommends", "Description")}
depends = fields["Depends"]
print("Depends:", depends)
for library in ("libc6", "libstdc++6", "libmodbus5", "libyaml-cpp0.7", "libsystemd0",
                "libmicrohttpd12", "libmosquitto1", "libspdlog1"):
    check(library in depends, f"depends on {library}")
for test_only in ("chromium", "qemu", "prometheus", "python3", "googletest", "libgtest",
                  "libbenchmark", "mosquitto ", "socat", "clang"):
    check(test_only not in depends, f"no dependency on {test_only.strip()}")

root = SCRATCH / "root"
control = SCRATCH / "control"
check(run("dpkg-deb", "-x", deb, root).returncode == 0, "the package extracts")
check(run("dpkg-deb", "-e", deb, control).returncode == 0, "its control files extract")

binary = root / "usr/bin/leakmon"
check(binary.is_file(), "the binary is /usr/bin/leakmon")
described = run("file", "-b", binary).stdout
check(", stripped" in described, f"the binary is stripped ({described.strip()})")
check(binary.stat().st_size < 20e6, f"... and small ({binary.stat().st_size / 1e6:.1f} MB)")
version = run(binary, "--version").stdout.strip()
check(re.fullmatch(r"leakmon \d+\.\d+\.\d+", version) is not None, f"--version: {version}")

conffiles = (control / "conffiles").read_text().split() if (control / "conffiles").exists() else []
check(conffiles == ["/etc/leakmon/leakmon.yaml", "/etc/logrotate.d/leakmon"],
      f"conffiles: the configuration and the rotation ({conffiles})")
for script in ("postinst", "prerm", "postrm"):
    path = control / script
    check(path.is_file() and os.access(path, os.X_OK), f"maintainer script {script}")

unit_files = glob.glob(str(root / "lib/systemd/system/leakmon.service")) + \
    glob.glob(str(root / "usr/lib/systemd/system/leakmon.service"))
check(len(unit_files) == 1, f"one unit file ({unit_files})")
unit = pathlib.Path(unit_files[0]).read_text() if unit_files else ""
check("ExecStart=/usr/bin/leakmon run --config /etc/leakmon/leakmon.yaml" in unit,
      "the unit runs /usr/bin/leakmon with /etc/leakmon/leakmon.yaml")
check(re.search(r"^ExecStartPre=/usr/bin/leakmon check-config --no-peers "
                r"/etc/leakmon/leakmon.yaml$", unit, re.M) is not None,
      "its pre-flight does not depend on peers being up at boot")
status_help = run(binary, "status", "--help").stdout
check("(default: /etc/leakmon/leakmon.yaml)" in status_help,
      "`leakmon status` looks where the unit looks")

template = root / "etc/leakmon/leakmon.yaml"
text = template.read_text() if template.exists() else ""
check(re.search(r"^\s+type: (modbus|can)\s", text, re.M) is not None,
      "the configuration is a real rig's: a Modbus or CAN driver")
check("type: sim" not in text and "onset_s" not in text, "... not the simulated demo leak")
check(re.search(r"^  log: /var/lib/leakmon/events.jsonl", text, re.M) is not None,
      "events under /var/lib/leakmon")
check(re.search(r"^  directory: /var/lib/leakmon\s", text, re.M) is not None,
      "learned state kept in /var/lib/leakmon")
check(text.count("\n#") >= 10, "commented")
# The template passes the file checks (as any user: its /var/lib/leakmon becomes a scratch dir).
scratch_var = SCRATCH / "var-lib-leakmon"
local_template = SCRATCH / "leakmon.yaml"
local_template.write_text(text.replace("/var/lib/leakmon", str(scratch_var)))
checked = run(binary, "check-config", "--no-probe", local_template)
check(checked.returncode == 0, f"check-config --no-probe accepts it: {checked.stdout}{checked.stderr}")

for path in ("usr/share/leakmon/prometheus/leakmon-alert-rules.yml",
             "usr/share/leakmon/prometheus/leakmon-recording-rules.yml",
             "usr/share/bash-completion/completions/leakmon",
             "etc/logrotate.d/leakmon",
             "usr/share/doc/leakmon/daemon.md"):
    check((root / path).is_file(), f"/{path}")
rotation = (root / "etc/logrotate.d/leakmon").read_text() if (root / "etc/logrotate.d/leakmon").exists() else ""
check("/var/lib/leakmon/events.jsonl {" in rotation, "rotation of the event log")

man = root / "usr/share/man/man1/leakmon.1.gz"
check(man.is_file(), "the man page leakmon(1)")
if man.is_file():
    page = gzip.decompress(man.read_bytes()).decode()
    check(".SH SUBCOMMANDS" in page and ".SS probe" in page and ".SS check-config" in page,
          "it describes every subcommand")
    check(".TH LEAKMON \"1\"" in page and "leakmon check-config" in page,
          "a section-1 page with the commissioning commands")

stray = [p for p in root.rglob("*") if p.is_file() and "test" in p.name.lower()
         and "promtool" not in str(p) and "tests" not in p.parts]
check(not stray, f"no test programs in the package ({stray})")

print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
