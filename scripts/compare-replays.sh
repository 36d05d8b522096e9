#!/usr/bin/env bash
# Replays the same captures through two leakmon builds and compares their event files: the check
# that a refactor changes no behaviour (docs/developing.md "A change that must not change
# behaviour").
#
# usage: scripts/compare-replays.sh BEFORE_LEAKMON AFTER_LEAKMON [WORK_DIR=/tmp/compare-replays]
#
# Simulates every sim/scenarios/*.yaml once (with BEFORE), replays each capture with the
# built-in configuration and with one configuration per detector kind (paper, index_cusum,
# flow_balance, fused, detail_xcorr; latching alarm), and compares the events line for line with
# each event's `time` removed: it is the wall-clock time of publication, different on every run.
# Prints one line per differing file and a summary; exit status 1 when any file differs.
set -euo pipefail
before=$1
after=$2
work=${3:-/tmp/compare-replays}
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$work/captures" "$work/before" "$work/after"

kinds=(paper index_cusum flow_balance fused detail_xcorr)
for kind in "${kinds[@]}"; do
  cat > "$work/$kind.yaml" <<YAML
drivers: [{name: rig, type: sim, scenario: healthy}]
sampling: [{name: main, period_ms: 2, drivers: [rig], priority: 0}]
actuators:
  - name: cylinder
    channels: {p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x}
    detector: {kind: $kind}
    alarm: {on_delay_s: 1, off_delay_s: 10, latching: true}
metrics: {port: 0}
state: {directory: ""}
YAML
done

for scenario in "$root"/sim/scenarios/*.yaml; do
  name=$(basename "$scenario" .yaml)
  capture="$work/captures/$name.csv"
  [ -f "$capture" ] || "$before" sim --scenario "$scenario" --out "$capture" > /dev/null
done

replay() {  # BINARY OUT_DIR
  for capture in "$work"/captures/*.csv; do
    name=$(basename "$capture" .csv)
    "$1" replay --in "$capture" --events "$2/$name-default.jsonl" > /dev/null 2>&1
    for kind in "${kinds[@]}"; do
      "$1" replay --in "$capture" --config "$work/$kind.yaml" --events "$2/$name-$kind.jsonl" \
        > /dev/null 2>&1
    done
  done
}
replay "$before" "$work/before"
replay "$after" "$work/after"

same=0
differ=0
for file in "$work"/before/*.jsonl; do
  name=$(basename "$file")
  if cmp -s <(sed 's/, "time": "[^"]*"//' "$file") \
            <(sed 's/, "time": "[^"]*"//' "$work/after/$name"); then
    same=$((same + 1))
  else
    differ=$((differ + 1))
    echo "differs: $name"
  fi
done
echo "$same event files identical, $differ different ($(cat "$work"/before/*.jsonl | wc -l) events)"
[ "$differ" -eq 0 ]
