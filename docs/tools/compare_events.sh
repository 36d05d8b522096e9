#!/bin/bash
# Byte-compares what two builds of leakmon decide, for a change that must not change detection
# (issue 26: detect/'s sequential-test core). Usage:
#
#   docs/tools/compare_events.sh BEFORE/leakmon AFTER/leakmon [WORKDIR] [--quick]
#
# 1. Captures: every sim/scenarios/*.yaml (its own seed and length) and the presets paper-fig10,
#    paper-fig13, paper-fig16 (seeds 1-3, their 30 s and 600 s), each recorded without and with
#    the `ps` and `temp` columns, all simulated by BEFORE (both builds read the same samples).
# 2. `leakmon replay` of each capture with one configuration of many actuators: the built-in
#    default (u, x and whatever else the capture has), p1 + p2 only, p1 only, index_cusum (both
#    chambers; p1 alone without ps: the hold-level supply), paper (p1; p2), fused, flow_balance,
#    detail_xcorr (both; p1; with temp), options that switch drift following and supply
#    estimation, and short learning periods so the 30 s presets are judged. Also the built-in
#    replay configuration alone (no --config). The events (one JSON line each, the wall-clock
#    `time` field removed) must be byte-identical.
# 3. Restarts: captures cut in two; BEFORE replays the first part with --state-dir, then BEFORE
#    and AFTER each replay the second part from a copy of that state directory: the state files
#    of BEFORE must load in AFTER and give the same events. And AFTER -> AFTER must give what
#    BEFORE -> BEFORE gave (AFTER's own state round trip).
# 4. `leakmon evaluate` (both builds simulate and replay the same runs): about 3 h of healthy,
#    leak and sensor-fault runs, healthy and leak runs under each drifting condition (stationary,
#    warmup, cooler, supply, sensor-faults, restart), every candidate detector on each (so about
#    3 h per detector); every output file must be byte-identical.
# --quick: the scenarios and presets only at their own length and fewer evaluate runs.
# --only=LIST: only these parts, of replay (2), restarts (3) and evaluate (4), comma-separated.
# --evaluate-args="ARGS": the `leakmon evaluate` options of part 4 instead of the ones below
#   (give --seed and --jobs too), for a sample of chosen length and conditions.
# Prints one line per comparison and a summary; exit status 1 when anything differs.
set -euo pipefail

usage="usage: compare_events.sh BEFORE AFTER [WORKDIR] [--quick] [--only=LIST] [--evaluate-args=ARGS]"
BEFORE=$(realpath "${1:?$usage}")
AFTER=$(realpath "${2:?$usage}")
WORK=/tmp/leakmon-compare-events
QUICK=0
PARTS=replay,restarts,evaluate
EVALUATE_ARGS=""
for arg in "${@:3}"; do
  case $arg in
    --quick) QUICK=1 ;;
    --only=*) PARTS=${arg#--only=} ;;
    --evaluate-args=*) EVALUATE_ARGS=${arg#--evaluate-args=} ;;
    --*) echo "$usage" >&2; exit 2 ;;
    *) WORK=$arg ;;
  esac
done
# part NAME: whether NAME was asked for.
part() { [[ ,$PARTS, == *,$1,* ]]; }
SOURCE=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$WORK"
cd "$WORK"

same=0
different=0
# compare LABEL FILE_BEFORE FILE_AFTER
compare() {
  if cmp -s "$2" "$3"; then
    same=$((same + 1))
    printf 'same       %-58s %6s lines\n' "$1" "$(wc -l <"$2")"
  else
    different=$((different + 1))
    printf 'DIFFERENT  %-58s (%s)\n' "$1" "$(cmp "$2" "$3" 2>&1 | head -1)"
  fi
}
# Events without the wall-clock time of publication.
strip_time() { sed -E 's/, "time": "[^"]*"//' "$1"; }

# The actuators of one replay configuration; $1: "pt" when the capture has ps and temp.
write_config() {
  local capture=$1 extra="" temp=""
  if [[ $2 == pt ]]; then
    extra=", ps: cap.ps, temp: cap.temp"
    temp=", temp: cap.temp"
  fi
  local all="p1: cap.p1, p2: cap.p2, u: cap.u, x: cap.x, xref: cap.xref"
  local short="settle_seconds: 1, learn_seconds: 12"
  cat <<EOF
drivers:
  - {name: cap, type: replay, path: $capture}
sampling:
  - {name: main, period_ms: 2, drivers: [cap]}
actuators:
  - {name: default_ux, channels: {$all$extra}}
  - {name: default_p1p2, channels: {p1: cap.p1, p2: cap.p2$extra}}
  - {name: default_p1, channels: {p1: cap.p1$extra}}
  - {name: index_p1p2, channels: {p1: cap.p1, p2: cap.p2$extra}, detector: index_cusum}
  - {name: index_p1_holds, channels: {p1: cap.p1$temp}, detector: index_cusum}
  - name: index_no_drift
    channels: {p1: cap.p1, p2: cap.p2$extra}
    detector: {kind: index_cusum, options: {drift_window_seconds: 0, temperature_prior: 0.3}}
  - {name: paper_p1, channels: {p1: cap.p1, p2: cap.p2}, detector: paper}
  - name: paper_p2
    channels: {p1: cap.p1, p2: cap.p2}
    detector: {kind: paper, options: {channel: p2, window_seconds: 4}}
  - {name: fused, channels: {$all$extra}, detector: fused}
  - {name: flow, channels: {$all$extra}, detector: flow_balance}
  - name: flow_rest_supply_off
    channels: {$all$temp}
    detector: {kind: flow_balance, options: {estimate_supply: false, drift_guard_seconds: 10}}
  - {name: xcorr_p1p2, channels: {p1: cap.p1, p2: cap.p2$extra}, detector: detail_xcorr}
  - {name: xcorr_p1, channels: {p1: cap.p1}, detector: detail_xcorr}
  - name: short_flow
    channels: {$all$extra}
    detector: {kind: flow_balance, options: {$short}}
  - name: short_index_p1
    channels: {p1: cap.p1}
    detector: {kind: index_cusum, options: {$short, drift_window_seconds: 8, drift_guard_seconds: 2}}
  - name: short_xcorr
    channels: {p1: cap.p1, p2: cap.p2$extra}
    detector: {kind: detail_xcorr, options: {settle_seconds: 1, learn_seconds: 16}}
  - name: short_paper
    channels: {p1: cap.p1}
    detector: {kind: paper, options: {$short, window_seconds: 2}}
  - name: short_fused
    channels: {$all$extra}
    detector: {kind: fused, options: {$short, block_seconds: 0.4}}
EOF
}

# replay_both NAME CAPTURE VARIANT: the configuration above and the built-in default.
replay_both() {
  local name=$1 capture=$2 variant=$3
  part replay || return 0
  write_config "$capture" "$variant" >"$name.yaml"
  for who in before after; do
    local exe=$BEFORE
    [[ $who == after ]] && exe=$AFTER
    nice "$exe" replay --in "$capture" --config "$name.yaml" --events "$name.$who.raw" 2>/dev/null
    strip_time "$name.$who.raw" >"$name.$who.jsonl"
    nice "$exe" replay --in "$capture" --events "$name.builtin.$who.raw" 2>/dev/null
    strip_time "$name.builtin.$who.raw" >"$name.builtin.$who.jsonl"
  done
  compare "replay $name" "$name.before.jsonl" "$name.after.jsonl"
  compare "replay $name (built-in configuration)" "$name.builtin.before.jsonl" \
    "$name.builtin.after.jsonl"
}

# restart NAME CAPTURE VARIANT FRACTION: cut the capture, learn on the first part, resume.
restart() {
  local name=$1 capture=$2 variant=$3 fraction=$4
  part restarts || return 0
  local header rows cut
  header=$(grep -c -E '^(#|t,)' "$capture")
  rows=$(($(wc -l <"$capture") - header))
  cut=$((rows * fraction / 100))
  head -n "$((header + cut))" "$capture" >"$name.part1.csv"
  { head -n "$header" "$capture"; tail -n "+$((header + cut + 1))" "$capture"; } >"$name.part2.csv"
  write_config "$name.part1.csv" "$variant" >"$name.part1.yaml"
  write_config "$name.part2.csv" "$variant" >"$name.part2.yaml"
  # Every replay uses the same directory name: events name the state file they restored.
  local state=$name.state
  rm -rf "$state" "$name.saved."*
  nice "$BEFORE" replay --in "$name.part1.csv" --config "$name.part1.yaml" \
    --events "$name.first.before.raw" --state-dir "$state" 2>/dev/null
  mv "$state" "$name.saved.before"
  nice "$AFTER" replay --in "$name.part1.csv" --config "$name.part1.yaml" \
    --events "$name.first.after.raw" --state-dir "$state" 2>/dev/null
  mv "$state" "$name.saved.after"
  # bb: before's state, before resumes; ba: before's state, after resumes; aa: after's, after.
  for run in bb ba aa; do
    local saved=$name.saved.before exe=$BEFORE
    [[ $run == aa ]] && saved=$name.saved.after
    [[ $run != bb ]] && exe=$AFTER
    cp -r "$saved" "$state"
    nice "$exe" replay --in "$name.part2.csv" --config "$name.part2.yaml" \
      --events "$name.$run.raw" --state-dir "$state" 2>/dev/null
    rm -rf "$state"
  done
  for run in first.before first.after bb ba aa; do strip_time "$name.$run.raw" >"$name.$run.jsonl"; done
  local restored
  restored=$(grep -c '"state_restored"' "$name.ba.jsonl" || true)
  compare "restart $name: first part" "$name.first.before.jsonl" "$name.first.after.jsonl"
  compare "restart $name: before's state, after resumes ($restored restored)" \
    "$name.bb.jsonl" "$name.ba.jsonl"
  compare "restart $name: after's own state" "$name.bb.jsonl" "$name.aa.jsonl"
  rm -f "$name.part1.csv" "$name.part2.csv"
}

echo "# leakmon compare_events: $BEFORE (before) vs $AFTER (after), in $WORK"

if part replay || part restarts; then
echo "## replay"
for scenario in "$SOURCE"/sim/scenarios/*.yaml; do
  base=$(basename "$scenario" .yaml)
  for variant in plain pt; do
    record=()
    [[ $variant == pt ]] && record=(--record ps,temp)
    nice "$BEFORE" sim --scenario "$scenario" --out "$base.$variant.csv" "${record[@]}" \
      >/dev/null 2>&1
    replay_both "$base.$variant" "$base.$variant.csv" "$variant"
    if [[ $variant == pt && ($base == morning-start || $base == supply-setpoint-change ||
      $base == oil-cooler-cycle || $base == sensor-faults) ]]; then
      restart "$base.$variant" "$base.$variant.csv" "$variant" 55
    fi
    if [[ $variant == plain && $base == external-leak-onset ]]; then
      restart "$base.$variant" "$base.$variant.csv" "$variant" 40
    fi
    rm -f "$base.$variant.csv"
  done
done
durations=(default 600)
[[ $QUICK == 1 ]] && durations=(default)
for preset in paper-fig10 paper-fig13 paper-fig16; do
  for seed in 1 2 3; do
    for duration in "${durations[@]}"; do
      for variant in plain pt; do
        name="$preset.s$seed.$duration.$variant"
        args=(--preset "$preset" --seed "$seed")
        [[ $duration != default ]] && args+=(--duration "$duration")
        [[ $variant == pt ]] && args+=(--record ps,temp)
        nice "$BEFORE" sim "${args[@]}" --out "$name.csv" >/dev/null 2>&1
        replay_both "$name" "$name.csv" "$variant"
        if [[ $duration == 600 && $seed == 2 ]]; then restart "$name" "$name.csv" "$variant" 50; fi
        rm -f "$name.csv"
      done
    done
  done
done

fi

if part evaluate; then
echo "## evaluate"
# Healthy and leak runs cycle through the six conditions (each leak size's runs too); the
# second six sensor-fault runs have a leak open during the fault.
evaluate=(--healthy-runs 6 --healthy-seconds 600 --runs-per-leak 6 --leaks 5e-13,2e-12
  --sensor-fault-runs 12 --conditions stationary,warmup,cooler,supply,sensor-faults,restart
  --seed 26 --jobs 2)
[[ $QUICK == 1 ]] && evaluate=(--healthy-runs 2 --healthy-seconds 400 --runs-per-leak 1
  --leaks 1e-12,5e-12 --sensor-fault-runs 2 --conditions warmup,restart --seed 26 --jobs 2)
# shellcheck disable=SC2206 # the options are words
[[ -n $EVALUATE_ARGS ]] && evaluate=($EVALUATE_ARGS)
echo "evaluate ${evaluate[*]}"
for who in before after; do
  exe=$BEFORE
  [[ $who == after ]] && exe=$AFTER
  rm -rf "evaluate.$who"
  nice "$exe" evaluate --out "evaluate.$who" "${evaluate[@]}" >/dev/null 2>&1
done
for file in evaluate.before/*; do
  compare "evaluate $(basename "$file")" "$file" "evaluate.after/$(basename "$file")"
done
echo "evaluate: $(grep -c '"id"' evaluate.before/runs.json) runs ($(grep -o '"operating": "[a-z-]*"' \
  evaluate.before/runs.json | sort | uniq -c | awk '{printf "%s%s %s", (NR > 1 ? ", " : ""), $1, $3}' |
  tr -d '"')), $(sed -nE \
  's/.*"seconds": ([0-9.e+]+),.*/\1/p' evaluate.before/runs.json |
  awk '{s += $1} END {printf "%.2f h simulated", s / 3600}')"
fi

echo "## summary: $same same, $different different"
[[ $different == 0 ]]
