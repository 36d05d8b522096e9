#!/usr/bin/python3
"""Shows that the promtool unit tests of prometheus/*rules.yml test every alert both ways.

For every alert rule: the test files have evaluations where it must fire and where it must
not; the tests pass as shipped; the firing checks of the alert, run alone, fail when the rule
never fires (`vector(1) == 0`), and its silent checks, run alone, fail when it always fires
(`vector(1)` without `for:`). Usage: check_rule_tests.py PROMTOOL PROMETHEUS_DIR
"""
import pathlib
import shutil
import subprocess
import sys
import tempfile

import yaml


def fail(message):
    print(f"FAIL: {message}")
    sys.exit(1)


def promtool_test(promtool, test_file):
    run = subprocess.run([promtool, "test", "rules", str(test_file)], capture_output=True,
                         text=True, timeout=50)
    return run.returncode, run.stdout + run.stderr


def main():
    promtool, source = sys.argv[1], pathlib.Path(sys.argv[2])
    rule_files = sorted(source.glob("*rules.yml"))
    test_files = sorted((source / "tests").glob("*.test.yml"))
    if not rule_files or not test_files:
        fail(f"no *rules.yml or tests/*.test.yml under {source}")

    alerts = {}  # alert name -> rule file
    for path in rule_files:
        for group in yaml.safe_load(path.read_text())["groups"]:
            for rule in group["rules"]:
                if "alert" in rule:
                    alerts[rule["alert"]] = path.name
    if not alerts:
        fail("no alert rules found")

    firing, silent = set(), set()
    for path in test_files:
        document = yaml.safe_load(path.read_text())
        for test in document["tests"]:
            for check in test.get("alert_rule_test", []):
                name = check["alertname"]
                if name not in alerts:
                    fail(f"{path.name}: tests unknown alert {name}")
                (firing if check.get("exp_alerts") else silent).add(name)
    for name in sorted(alerts):
        if name not in firing:
            fail(f"alert {name} has no test where it fires")
        if name not in silent:
            fail(f"alert {name} has no test where it must not fire")

    for path in test_files:
        code, output = promtool_test(promtool, path)
        if code != 0:
            fail(f"promtool test rules {path} as shipped:\n{output}")

    # Each alert's firing checks alone must notice a rule that never fires, and its silent
    # checks alone a rule that fires at once and always (a label-less alert, `for:` removed).
    mutations = {True: "vector(1) == 0", False: "vector(1)"}
    with tempfile.TemporaryDirectory() as scratch:
        work = pathlib.Path(scratch)
        (work / "tests").mkdir()
        for name, file_name in sorted(alerts.items()):
            for expect_firing, mutation in mutations.items():
                kind = "firing" if expect_firing else "silent"
                tests_only = work / "tests" / "only.test.yml"
                selected = 0
                for path in test_files:
                    document = yaml.safe_load(path.read_text())
                    kept = []
                    for test in document["tests"]:
                        checks = [c for c in test.get("alert_rule_test", [])
                                  if c["alertname"] == name
                                  and bool(c.get("exp_alerts")) == expect_firing]
                        if checks:
                            test = dict(test, alert_rule_test=checks)
                            test.pop("promql_expr_test", None)
                            kept.append(test)
                            selected += len(checks)
                    if kept:
                        document["tests"] = kept
                        break
                tests_only.write_text(yaml.safe_dump(document, sort_keys=False))
                for original in (True, False):
                    for path in rule_files:
                        rules = yaml.safe_load(path.read_text())
                        if not original and path.name == file_name:
                            for group in rules["groups"]:
                                for rule in group["rules"]:
                                    if rule.get("alert") == name:
                                        rule["expr"] = mutation
                                        rule.pop("for", None)
                        (work / path.name).write_text(yaml.safe_dump(rules, sort_keys=False))
                    code, output = promtool_test(promtool, tests_only)
                    if original and code != 0:
                        fail(f"{name}: its {kind} checks alone fail:\n{output}")
                    if not original and code == 0:
                        fail(f"{name}: its {kind} checks still pass with the rule as `{mutation}`")
                print(f"ok: {name}: {selected} {kind} check(s) catch the rule as `{mutation}`")
    print(f"{len(alerts)} alerts, each tested firing and silent, mutations caught")


if __name__ == "__main__":
    main()
