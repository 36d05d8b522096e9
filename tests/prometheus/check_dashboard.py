#!/usr/bin/python3
"""Checks the Grafana dashboard (and the rules) against a live /metrics scrape of the daemon.

check_dashboard.py [--promtool PROMTOOL] DASHBOARD.json SCRAPE.txt [RULES.yml ...]

The dashboard must parse as JSON, take its Prometheus data source from a `datasource`
template variable (so that it imports into any Grafana), and every PromQL expression in it
(panel targets and template queries) may name only metrics present in SCRAPE (the daemon's
exposition; histogram series by their _bucket/_sum/_count names). The gauges of issue 14
must each be on some panel; panel ids are unique and every panel lies in Grafana's 24-column
grid. With --promtool, every expression (Grafana's variables replaced by values, label_values()
by its selector) must parse as PromQL: they are handed to `promtool check rules` as recording
rules. Rule expressions may also name `up` (Prometheus' own series). Exits non-zero naming
every problem.
"""
import json
import pathlib
import re
import subprocess
import sys
import tempfile

import yaml

# PromQL functions and aggregations (Prometheus 2.42), and Grafana's label_values().
FUNCTIONS = set("""
abs absent absent_over_time avg_over_time ceil changes clamp clamp_max clamp_min
count_over_time day_of_month day_of_week day_of_year days_in_month delta deriv exp floor
histogram_count histogram_fraction histogram_quantile histogram_sum holt_winters hour idelta
increase irate label_join label_replace last_over_time ln log10 log2 max_over_time
min_over_time minute month predict_linear present_over_time quantile_over_time rate resets
round scalar sgn sort sort_desc sqrt stddev_over_time stdvar_over_time sum_over_time time
timestamp vector year sum min max avg group stddev stdvar count count_values bottomk topk
quantile label_values acos acosh asin asinh atan atanh cos cosh deg pi rad sin sinh tan tanh
""".split())
KEYWORDS = {"and", "or", "unless", "bool", "offset", "by", "without", "on", "ignoring",
            "group_left", "group_right", "inf", "nan"}
# Gauges issue 14 asks for; each must be shown somewhere.
REQUIRED_ON_DASHBOARD = ["leakmon_leak_lpm_per_mpa", "leakmon_leak_lpm_per_mpa_ci95",
                         "leakmon_oil_temperature_celsius", "leakmon_sensor_status",
                         "leakmon_learned_state_age_seconds", "leakmon_alarm_active"]


def scraped_names(text):
    names = set()
    for line in text.splitlines():
        if line and not line.startswith("#"):
            names.add(re.split(r"[{ ]", line, maxsplit=1)[0])
    return names


def metric_names(expr):
    """The metric names an expression selects (functions, keywords, labels set aside)."""
    text = re.sub(r'"(?:[^"\\]|\\.)*"|\'(?:[^\'\\]|\\.)*\'', '""', expr)
    text = re.sub(r"\$\{[^}]*\}|\$\w+", "", text)
    text = re.sub(r"\[[^\]]*\]", "", text)
    text = re.sub(r"\{[^}]*\}", "", text)
    text = re.sub(r"\b(by|without|on|ignoring|group_left|group_right)\s*\([^)]*\)", "", text)
    # label_values(SELECTOR, LABEL): the last argument is a label name.
    text = re.sub(r"(label_values\s*\(.*),\s*[A-Za-z_]\w*\s*\)", r"\1)", text)
    text = re.sub(r"\b\d+(\.\d+)?([eE][+-]?\d+)?\b", "", text)
    names = []
    for match in re.finditer(r"[A-Za-z_:][A-Za-z0-9_:]*", text):
        word = match.group(0)
        following = text[match.end():].lstrip()
        if following.startswith("("):
            if word not in FUNCTIONS:
                raise ValueError(f"unknown function {word}")
            continue
        if word.lower() in KEYWORDS:
            continue
        names.append(word)
    return names


def dashboard_exprs(dashboard):
    exprs = []

    def panels_of(panels):
        for panel in panels:
            yield panel
            yield from panels_of(panel.get("panels", []))

    for panel in panels_of(dashboard.get("panels", [])):
        if panel.get("type") != "row":
            if panel.get("datasource", {}).get("uid") != "${datasource}":
                yield None, f"panel '{panel.get('title')}' does not use the ${{datasource}} variable"
        for target in panel.get("targets", []):
            if target.get("datasource", {}).get("uid") not in (None, "${datasource}"):
                yield None, f"a target of panel '{panel.get('title')}' has a fixed data source"
            exprs.append((f"panel '{panel.get('title')}'", target.get("expr", "")))
    for variable in dashboard.get("templating", {}).get("list", []):
        if variable.get("type") == "query":
            query = variable.get("query")
            if isinstance(query, dict):
                query = query.get("query", "")
            exprs.append((f"variable {variable.get('name')}", query))
    for where, expr in exprs:
        yield (where, expr), None


def as_promql(expr):
    """A Grafana expression as plain PromQL: variables given values, label_values() unwrapped."""
    text = re.sub(r"\$__(rate_)?interval\b|\$\{__(rate_)?interval\}", "1m", expr)
    text = re.sub(r"\$\{[^}]*\}|\$\w+", ".*", text)
    return re.sub(r"^\s*label_values\s*\((.*),\s*[A-Za-z_]\w*\s*\)\s*$", r"\1", text)


def promql_problems(promtool, exprs):
    """What `promtool check rules` says about the expressions as recording rules."""
    rules = {"groups": [{"name": "dashboard", "rules": [
        {"record": f"dashboard:expr_{i}", "expr": as_promql(expr)}
        for i, (_, expr) in enumerate(exprs)]}]}
    with tempfile.NamedTemporaryFile("w", suffix=".yml") as file:
        file.write(yaml.safe_dump(rules))
        file.flush()
        run = subprocess.run([promtool, "check", "rules", file.name], capture_output=True,
                             text=True, timeout=50)
    if run.returncode == 0:
        return []
    return [f"an expression does not parse as PromQL: {run.stdout + run.stderr}"]


def layout_problems(dashboard):
    problems, ids = [], set()

    def walk(panels):
        for panel in panels:
            title, pos = panel.get("title"), panel.get("gridPos", {})
            if panel.get("id") in ids:
                problems.append(f"panel '{title}': id {panel.get('id')} used twice")
            ids.add(panel.get("id"))
            if not title:
                problems.append(f"panel {panel.get('id')} has no title")
            x, w, h = pos.get("x", -1), pos.get("w", 0), pos.get("h", 0)
            if not (0 <= x and w > 0 and h > 0 and x + w <= 24 and pos.get("y", -1) >= 0):
                problems.append(f"panel '{title}': gridPos {pos} is not in the 24-column grid")
            walk(panel.get("panels", []))

    walk(dashboard.get("panels", []))
    return problems


def main():
    arguments = sys.argv[1:]
    promtool = None
    if arguments[:1] == ["--promtool"]:
        promtool, arguments = arguments[1], arguments[2:]
    dashboard_path, scrape_path = pathlib.Path(arguments[0]), pathlib.Path(arguments[1])
    emitted = scraped_names(scrape_path.read_text())
    problems = []
    if not any(name.startswith("leakmon_") for name in emitted):
        problems.append(f"{scrape_path}: no leakmon_ series (not a leakmon scrape)")
    try:
        dashboard = json.loads(dashboard_path.read_text())
    except json.JSONDecodeError as error:
        print(f"FAIL: {dashboard_path}: not JSON: {error}")
        return 1
    if not dashboard.get("title"):
        problems.append("the dashboard has no title")
    problems += layout_problems(dashboard)
    variables = dashboard.get("templating", {}).get("list", [])
    if not any(v.get("name") == "datasource" and v.get("type") == "datasource"
               and v.get("query") == "prometheus" for v in variables):
        problems.append("no `datasource` template variable of type datasource (prometheus)")
    shown = set()
    count = 0
    all_exprs = []
    for item, problem in dashboard_exprs(dashboard):
        if problem:
            problems.append(problem)
            continue
        where, expr = item
        all_exprs.append(item)
        count += 1
        try:
            names = metric_names(expr)
        except ValueError as error:
            problems.append(f"{where}: {error} in `{expr}`")
            continue
        if not names:
            problems.append(f"{where}: `{expr}` selects no metric")
        for name in names:
            shown.add(name)
            if name not in emitted:
                problems.append(f"{where}: {name} is not emitted by the daemon (`{expr}`)")
    if count == 0:
        problems.append("the dashboard has no PromQL expression")
    elif promtool:
        problems += promql_problems(promtool, all_exprs)
    for name in REQUIRED_ON_DASHBOARD:
        if name not in shown:
            problems.append(f"no panel shows {name}")

    for rules_path in map(pathlib.Path, arguments[2:]):
        for group in yaml.safe_load(rules_path.read_text())["groups"]:
            for rule in group["rules"]:
                where = f"{rules_path.name}: {rule.get('alert') or rule.get('record')}"
                try:
                    names = metric_names(rule["expr"])
                except ValueError as error:
                    problems.append(f"{where}: {error}")
                    continue
                for name in names:
                    if name != "up" and name not in emitted:
                        problems.append(f"{where}: {name} is not emitted by the daemon")

    for problem in problems:
        print(f"FAIL: {problem}")
    if not problems:
        print(f"ok: {count} dashboard expressions name only the {len(emitted)} emitted series")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
