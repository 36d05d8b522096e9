// `leakmon evaluate`: Monte-Carlo error rates of the leak detectors. Draws rigs across MODEL.md's
// calibration spread (both controllers, spring 40-120 kN/m, beta, Kv, m, b, reference
// amplitudes and seeds), healthy runs and runs with a leak switched on mid-run, simulates each
// (sim/) and replays it in process through exactly the daemon's pipeline
// (daemon::replay_capture). Every detector under test is one actuator of the replayed
// configuration, at several alarm thresholds, so one replay yields the whole ROC sweep. Writes
// runs.json (every run and alarm), summary.json, summary.tsv and summary.md into --out, and the
// plots when --plots is given (docs/tools/detection_plots.py).
#include <fmt/format.h>
#include <fmt/os.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "capture/capture.hpp"
#include "daemon/cli/args.hpp"
#include "daemon/cli/subcommands.hpp"
#include "daemon/replay.hpp"
#include "detect/factory.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"

namespace leakmon::cli {

namespace {

constexpr double kLitresPerMinutePerMPa = 60000.0 * 1e6;  // m^3/(s Pa) -> l/min/MPa

// A detector as the daemon would be configured with it: which channels the actuator acquires,
// the detector kind, and the alarm thresholds swept for its ROC curve (the design point first).
struct Candidate {
  std::string label;  // as in the outputs
  std::string kind;   // detect::make_detector kind
  bool p2, u, x;      // channels besides p1
  std::vector<double> raise_thresholds;
  double design_threshold;
  double clear_gap;  // clear = raise * clear_ratio (or raise - clear_gap when > 0)
  double clear_ratio;
};

std::vector<Candidate> candidates() {
  const std::vector<double> cusum_grid = {0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0};
  return {
      {"paper", "paper", false, false, false, {0.6, 0.7, 0.8, 0.9, 0.95, 0.99}, 0.9, 0.2, 0.0},
      {"index_cusum_p1", "index_cusum", false, false, false, cusum_grid, 1.0, 0.0, 0.5},
      {"index_cusum", "index_cusum", true, false, false, cusum_grid, 1.0, 0.0, 0.5},
      {"flow_balance", "flow_balance", true, true, true, cusum_grid, 1.0, 0.0, 0.5},
      {"fused", "fused", true, true, true, cusum_grid, 1.0, 0.0, 0.5},
      {"default", "default", true, true, true, cusum_grid, 1.0, 0.0, 0.5},
  };
}

std::string actuator_name(std::size_t candidate, std::size_t threshold) {
  return fmt::format("c{}_t{}", candidate, threshold);
}

struct RunSpec {
  int id = 0;
  sim::Scenario scenario;
  double leak = 0.0;        // C_L [m^3/(s Pa)], 0 healthy
  double onset = 1e300;     // leak onset [s]
  double monitor_from = 0;  // end of settle + learning [s]
};

struct Alarm {
  double raised = 0.0;
  double leak_coefficient = NAN;
};

// The leak size and its 95 % interval that the flow balance reports when it first raises after
// the onset. The daemon's alarm event carries the size but not the interval, so the detector
// is run once more on the capture's hop means (the same Observation fields the worker fills).
struct SizeCheck {
  double t = NAN;
  double leak_coefficient = NAN;
  double half_width = NAN;
  bool covers(double truth) const { return std::abs(leak_coefficient - truth) <= half_width; }
};

struct RunResult {
  RunSpec spec;
  SizeCheck size_check;
  // [candidate][threshold] -> raise times and sizes
  std::vector<std::vector<std::vector<Alarm>>> alarms;
  double seconds = 0.0;
};

struct Settings {
  int healthy_runs = 8;
  double healthy_seconds = 900.0;
  int runs_per_leak = 6;
  std::vector<double> leak_sizes = {1e-13, 2.5e-13, 5e-13, 1e-12, 2e-12, 5e-12};
  double learn_seconds = 90.0;
  double settle_seconds = 2.0;
  double after_onset_seconds = 90.0;
  double detect_within = 60.0;
  std::uint64_t seed = 1;
  int jobs = 2;
  std::vector<std::string> effects;  // MODEL.md effect names on every run (default parameters)
  std::vector<int> keep_captures;    // run ids whose capture CSV is written into the output
  std::filesystem::path out;
};

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// A rig drawn across MODEL.md's calibration spread and the load range.
sim::Scenario draw_rig(std::mt19937_64& rng, int id, std::uint64_t seed, double duration,
                       const std::vector<std::string>& effects) {
  sim::Scenario s = sim::preset("healthy", seed);
  s.name = fmt::format("evaluate-{}", id);
  s.origin = fmt::format("leakmon evaluate run {}", id);
  s.controller = id % 2 == 0 ? sim::ControllerKind::basic : sim::ControllerKind::fault_tolerant;
  s.duration_s = duration;
  s.params.K_s = uniform(rng, 40e3, 120e3);
  s.params.beta *= uniform(rng, 0.75, 1.25);
  s.params.Kv *= uniform(rng, 0.9, 1.1);
  s.params.m *= uniform(rng, 0.8, 1.2);
  s.params.b *= uniform(rng, 0.7, 1.3);
  const double amplitude = uniform(rng, 0.6, 1.0);  // smaller steps excite the index less
  s.reference.amp_min *= amplitude;
  s.reference.amp_max *= amplitude;
  for (const auto& effect : effects) s.effects.enable(effect);
  return s;
}

std::vector<RunSpec> draw_runs(const Settings& settings) {
  std::mt19937_64 rng(settings.seed);
  std::vector<RunSpec> runs;
  const double monitor_from = settings.settle_seconds + settings.learn_seconds + 1.0;
  int id = 0;
  for (int i = 0; i < settings.healthy_runs; ++i, ++id) {
    RunSpec run;
    run.id = id;
    run.monitor_from = monitor_from;
    run.scenario =
        draw_rig(rng, id, settings.seed * 100003 + id, settings.healthy_seconds, settings.effects);
    runs.push_back(std::move(run));
  }
  for (double leak : settings.leak_sizes) {
    for (int i = 0; i < settings.runs_per_leak; ++i, ++id) {
      RunSpec run;
      run.id = id;
      run.monitor_from = monitor_from;
      run.leak = leak;
      // A healthy stretch after learning (false alarms count there too), then the leak.
      run.onset = monitor_from + uniform(rng, 20.0, 60.0);
      run.scenario = draw_rig(rng, id, settings.seed * 100003 + id,
                              run.onset + settings.after_onset_seconds, settings.effects);
      run.scenario.effects.internal_leakage = sim::InternalLeakage{leak, run.onset, 0.0};
      runs.push_back(std::move(run));
    }
  }
  return runs;
}

config::ConfigNode detector_options(const Settings& settings) {
  return config::ConfigNode::load_string(
      fmt::format("learn_seconds: {}\nsettle_seconds: {}\n", settings.learn_seconds,
                  settings.settle_seconds),
      "leakmon evaluate");
}

daemon::DaemonConfig evaluation_config(const capture::Capture& capture, const Settings& settings) {
  daemon::DaemonConfig config = daemon::default_replay_config(capture);
  const daemon::ActuatorConfig base = config.actuators.at(0);
  config.actuators.clear();
  const auto options = detector_options(settings);
  const auto all = candidates();
  for (std::size_t c = 0; c < all.size(); ++c) {
    const Candidate& candidate = all[c];
    for (std::size_t t = 0; t < candidate.raise_thresholds.size(); ++t) {
      daemon::ActuatorConfig a = base;
      a.name = actuator_name(c, t);
      a.detector = candidate.kind;
      a.detector_options = options;
      if (!candidate.p2) a.p2 = {};
      if (!candidate.u) a.u = {};
      if (!candidate.x) a.x = {};
      const double raise = candidate.raise_thresholds[t];
      a.alarm.raise_threshold = raise;
      a.alarm.clear_threshold =
          candidate.clear_gap > 0.0 ? raise - candidate.clear_gap : raise * candidate.clear_ratio;
      config.actuators.push_back(std::move(a));
    }
  }
  return config;
}

SizeCheck check_size(const capture::Capture& capture, const RunSpec& spec, const Settings& settings,
                     const config::ConfigNode& options) {
  constexpr std::size_t kStep = 20;  // the daemon's default hop
  const double hop_seconds = static_cast<double>(kStep) / capture.sample_rate_hz();
  const auto detector =
      detect::make_detector("flow_balance", {true, true, true, true}, hop_seconds, &options);
  const auto& t = capture.column("t");
  const auto &u = capture.column("u"), &x = capture.column("x");
  const auto &p1 = capture.column("p1"), &p2 = capture.column("p2");
  auto mean = [](const std::vector<double>& v, std::size_t from, std::size_t to) {
    double sum = 0.0;
    for (std::size_t i = from; i < to; ++i) sum += v[i];
    return sum / static_cast<double>(to - from);
  };
  SizeCheck check;
  for (std::size_t end = kStep; end <= capture.rows(); end += kStep) {
    detect::Observation o;
    o.t = t[end - 1];
    o.u = mean(u, end - kStep, end);
    o.x = mean(x, end - kStep, end);
    o.p1 = mean(p1, end - kStep, end);
    o.p2 = mean(p2, end - kStep, end);
    const detect::Decision decision = detector->update(o);
    if (o.t < spec.onset || !(decision.score >= detector->raise_threshold())) continue;
    if (o.t - spec.onset > settings.detect_within) break;
    check = {o.t, decision.leak_coefficient, decision.leak_coefficient_ci};
    break;
  }
  return check;
}

RunResult evaluate_run(const RunSpec& spec, const Settings& settings) {
  RunResult result;
  result.spec = spec;
  const capture::Capture capture = sim::simulate(spec.scenario);
  if (std::find(settings.keep_captures.begin(), settings.keep_captures.end(), spec.id) !=
      settings.keep_captures.end()) {
    capture::write_capture((settings.out / fmt::format("run-{}.csv", spec.id)).string(), capture);
  }
  const daemon::ReplayResult replay =
      daemon::replay_capture(capture, evaluation_config(capture, settings));
  if (spec.leak > 0.0) {
    result.size_check = check_size(capture, spec, settings, detector_options(settings));
  }
  const auto all = candidates();
  result.alarms.resize(all.size());
  std::map<std::string, std::pair<std::size_t, std::size_t>> by_name;
  for (std::size_t c = 0; c < all.size(); ++c) {
    result.alarms[c].resize(all[c].raise_thresholds.size());
    for (std::size_t t = 0; t < all[c].raise_thresholds.size(); ++t) {
      by_name[actuator_name(c, t)] = {c, t};
    }
  }
  for (const auto& event : replay.events) {
    if (event.kind != io::EventKind::alarm_raised) continue;
    const auto found = by_name.find(event.actuator);
    if (found == by_name.end()) continue;
    result.alarms[found->second.first][found->second.second].push_back(
        {event.t, event.leak_coefficient});
  }
  result.seconds = spec.scenario.duration_s;
  return result;
}

// Error rates of one candidate at one threshold over a set of runs.
struct Rates {
  double healthy_hours = 0.0;
  int false_alarms = 0;
  int leak_runs = 0, detected = 0;
  std::vector<double> delays;       // of runs detected within the window
  std::vector<double> size_errors;  // relative error of the size in the raising alarm
  double false_alarms_per_hour() const {
    return healthy_hours > 0 ? false_alarms / healthy_hours : NAN;
  }
  double detection_rate() const { return leak_runs > 0 ? double(detected) / leak_runs : NAN; }
  double median_delay() const {
    if (delays.empty()) return NAN;
    std::vector<double> d = delays;
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    return d[d.size() / 2];
  }
  double median_abs_size_error() const {
    if (size_errors.empty()) return NAN;
    std::vector<double> e;
    for (double v : size_errors) e.push_back(std::abs(v));
    std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
    return e[e.size() / 2];
  }
};

// Healthy time is everything monitored before the onset; a raise there is a false alarm. A leak
// counts as detected if an alarm is raised within `detect_within` seconds of the onset.
void add_run(Rates& rates, const RunResult& run, std::size_t c, std::size_t t,
             const Settings& settings, bool include_healthy, bool include_leak) {
  const RunSpec& spec = run.spec;
  const double healthy_end = std::min(spec.onset, run.seconds);
  const auto& alarms = run.alarms[c][t];
  if (include_healthy) {
    rates.healthy_hours += std::max(0.0, healthy_end - spec.monitor_from) / 3600.0;
    for (const auto& a : alarms) {
      if (a.raised < healthy_end) ++rates.false_alarms;
    }
  }
  if (include_leak && spec.leak > 0.0) {
    ++rates.leak_runs;
    for (const auto& a : alarms) {
      if (a.raised < spec.onset) continue;
      const double delay = a.raised - spec.onset;
      if (delay <= settings.detect_within) {
        ++rates.detected;
        rates.delays.push_back(delay);
        if (!std::isnan(a.leak_coefficient)) {
          rates.size_errors.push_back(a.leak_coefficient / spec.leak - 1.0);
        }
      }
      break;
    }
  }
}

std::string json_number(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "null"; }

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

std::vector<double> parse_list(const std::string& option, const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      values.push_back(std::stod(item));
    } catch (const std::exception&) {
      throw UsageError(fmt::format("option '--{}': '{}' is not a number", option, item));
    }
  }
  return values;
}

}  // namespace

int run_evaluate(int argc, char** argv) {
  ArgParser args("evaluate",
                 "Monte-Carlo error rates of the leak detectors on simulated rigs, each capture\n"
                 "replayed through the daemon's pipeline. Writes runs.json, summary.json,\n"
                 "summary.tsv and summary.md into --out (and plots with --plots).");
  args.option("out", "DIR", "output directory", std::nullopt, true)
      .option("healthy-runs", "N", "healthy runs (false-alarm rate)", "8")
      .option("healthy-seconds", "S", "length of each healthy run", "900")
      .option("runs-per-leak", "N", "runs per leak size", "6")
      .option("leaks", "LIST", "leak sizes C_L [m^3/(s Pa)], comma-separated",
              "1e-13,2.5e-13,5e-13,1e-12,2e-12,5e-12")
      .option("learn-seconds", "S", "each detector's learning period", "90")
      .option("after-onset", "S", "run length after the leak onset", "90")
      .option("seed", "N", "master seed", "1")
      .option("jobs", "N", "parallel runs", "2")
      .option("effects", "LIST",
              "MODEL.md effects switched on in every run (default parameters), comma-separated", "")
      .option("keep-captures", "IDS", "write these runs' captures (run-ID.csv), comma-separated",
              "")
      .flag("plots", "also draw the plots (matplotlib via /usr/bin/python3)")
      .option("plot-script", "PATH", "the plotting script", "docs/tools/detection_plots.py");
  if (!args.parse(argc, argv)) return 0;

  Settings settings;
  settings.healthy_runs = static_cast<int>(args.get_int("healthy-runs"));
  settings.healthy_seconds = args.get_double("healthy-seconds");
  settings.runs_per_leak = static_cast<int>(args.get_int("runs-per-leak"));
  settings.leak_sizes = parse_list("leaks", args.get("leaks"));
  settings.learn_seconds = args.get_double("learn-seconds");
  settings.after_onset_seconds = args.get_double("after-onset");
  settings.seed = static_cast<std::uint64_t>(args.get_int("seed"));
  settings.jobs = static_cast<int>(args.get_int("jobs"));
  settings.effects = split(args.get("effects"));
  for (const auto& effect : settings.effects) {
    try {
      sim::Effects().enable(effect);
    } catch (const std::exception& e) {
      throw UsageError(fmt::format("option '--effects': {}", e.what()));
    }
  }
  if (settings.healthy_runs < 0 || settings.runs_per_leak < 0 || settings.jobs < 1) {
    throw UsageError("run counts must be >= 0 and --jobs >= 1");
  }
  if (settings.learn_seconds < 1 || settings.healthy_seconds < settings.learn_seconds + 10 ||
      settings.after_onset_seconds < settings.detect_within) {
    throw UsageError(
        "need --learn-seconds >= 1, --healthy-seconds >= learn + 10, --after-onset >= 60");
  }
  for (double id : parse_list("keep-captures", args.get("keep-captures"))) {
    settings.keep_captures.push_back(static_cast<int>(id));
  }
  const std::filesystem::path out = args.get("out");
  settings.out = out;
  std::filesystem::create_directories(out);

  const std::vector<RunSpec> runs = draw_runs(settings);
  std::vector<RunResult> results(runs.size());
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex progress;
  std::string failure;
  auto worker = [&] {
    for (std::size_t i = next++; i < runs.size(); i = next++) {
      try {
        results[i] = evaluate_run(runs[i], settings);
      } catch (const std::exception& e) {
        std::lock_guard lock(progress);
        failure = fmt::format("run {}: {}", runs[i].id, e.what());
        next = runs.size();
        return;
      }
      std::lock_guard lock(progress);
      fmt::print(stderr, "\r[{}/{}] runs evaluated", ++done, runs.size());
      std::fflush(stderr);
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < settings.jobs; ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  fmt::print(stderr, "\n");
  if (!failure.empty()) throw std::runtime_error(failure);

  const auto all = candidates();
  // runs.json: every run with its rig and each candidate's alarms at the design threshold.
  {
    auto f = fmt::output_file((out / "runs.json").string());
    f.print("[\n");
    for (std::size_t i = 0; i < results.size(); ++i) {
      const auto& r = results[i];
      const auto& s = r.spec.scenario;
      f.print(
          "  {{\"id\": {}, \"controller\": \"{}\", \"seconds\": {}, \"leak\": {}, "
          "\"onset\": {}, \"K_s\": {}, \"beta\": {}, \"Kv\": {}, \"m\": {}, \"b\": {}, "
          "\"amp_max\": {}, \"alarms\": {{",
          r.spec.id, sim::to_string(s.controller), json_number(r.seconds), json_number(r.spec.leak),
          json_number(r.spec.leak > 0 ? r.spec.onset : NAN), json_number(s.params.K_s),
          json_number(s.params.beta), json_number(s.params.Kv), json_number(s.params.m),
          json_number(s.params.b), json_number(s.reference.amp_max));
      for (std::size_t c = 0; c < all.size(); ++c) {
        const auto design = static_cast<std::size_t>(std::find(all[c].raise_thresholds.begin(),
                                                               all[c].raise_thresholds.end(),
                                                               all[c].design_threshold) -
                                                     all[c].raise_thresholds.begin());
        f.print("{}\"{}\": [", c ? ", " : "", all[c].label);
        const auto& alarms = r.alarms[c][design];
        for (std::size_t a = 0; a < alarms.size(); ++a) {
          f.print("{}{{\"t\": {}, \"leak_coefficient\": {}}}", a ? ", " : "",
                  json_number(alarms[a].raised), json_number(alarms[a].leak_coefficient));
        }
        f.print("]");
      }
      const SizeCheck& size = r.size_check;
      f.print(
          "}}, \"size_at_raise\": {{\"t\": {}, \"leak_coefficient\": {}, "
          "\"half_width_95\": {}}}}}{}\n",
          json_number(size.t), json_number(size.leak_coefficient), json_number(size.half_width),
          i + 1 < results.size() ? "," : "");
    }
    f.print("]\n");
  }

  // Summaries: per candidate, per threshold (ROC) and per leak size and controller at the
  // design threshold.
  auto f_json = fmt::output_file((out / "summary.json").string());
  auto f_tsv = fmt::output_file((out / "summary.tsv").string());
  auto f_md = fmt::output_file((out / "summary.md").string());
  auto f_tsv_coverage = fmt::output_file((out / "size_coverage.tsv").string());
  f_tsv_coverage.print("controller\tleak\traised\tcovered\tmedian_relative_half_width\n");
  f_tsv.print(
      "detector\tcontroller\tleak\tthreshold\tdesign\tfa_per_hour\thealthy_hours\t"
      "detected\tleak_runs\tdetection_rate\tmedian_delay\tmedian_abs_size_error\n");
  f_md.print(
      "| detector | controller | C_L [m^3/(s Pa)] | l/min/MPa | detected within {:.0f} s | "
      "median delay [s] | false alarms / h (healthy h) | median size error |\n"
      "|---|---|---|---|---|---|---|---|\n",
      settings.detect_within);
  f_json.print(
      "{{\n  \"settings\": {{\"healthy_runs\": {}, \"healthy_seconds\": {}, "
      "\"runs_per_leak\": {}, \"learn_seconds\": {}, \"seed\": {}, "
      "\"detect_within\": {}, \"effects\": \"{}\"}},\n  \"detectors\": [\n",
      settings.healthy_runs, settings.healthy_seconds, settings.runs_per_leak,
      settings.learn_seconds, settings.seed, settings.detect_within,
      fmt::join(settings.effects, ","));
  const std::vector<std::string> controllers = {"all", "basic", "fault_tolerant"};
  for (std::size_t c = 0; c < all.size(); ++c) {
    f_json.print(
        "    {{\"name\": \"{}\", \"kind\": \"{}\", \"design_threshold\": {}, \"rows\": [\n",
        all[c].label, all[c].kind, all[c].design_threshold);
    bool first_row = true;
    for (std::size_t t = 0; t < all[c].raise_thresholds.size(); ++t) {
      const double threshold = all[c].raise_thresholds[t];
      const bool design = threshold == all[c].design_threshold;
      for (const auto& controller : controllers) {
        std::vector<double> sizes = {0.0};  // 0: all leak sizes pooled
        sizes.insert(sizes.end(), settings.leak_sizes.begin(), settings.leak_sizes.end());
        for (double size : sizes) {
          Rates rates;
          for (const auto& r : results) {
            const std::string_view ctrl = sim::to_string(r.spec.scenario.controller);
            if (controller != "all" && ctrl != controller) continue;
            const bool leak_match = size == 0.0 || r.spec.leak == size;
            add_run(rates, r, c, t, settings, true, leak_match);
          }
          f_tsv.print("{}\t{}\t{:g}\t{:g}\t{}\t{:.4g}\t{:.4g}\t{}\t{}\t{:.4g}\t{:.4g}\t{:.4g}\n",
                      all[c].label, controller, size, threshold, design ? 1 : 0,
                      rates.false_alarms_per_hour(), rates.healthy_hours, rates.detected,
                      rates.leak_runs, rates.detection_rate(), rates.median_delay(),
                      rates.median_abs_size_error());
          f_json.print(
              "{}      {{\"controller\": \"{}\", \"leak\": {}, \"threshold\": {}, "
              "\"design\": {}, \"false_alarms\": {}, \"healthy_hours\": {}, "
              "\"false_alarms_per_hour\": {}, \"leak_runs\": {}, \"detected\": {}, "
              "\"detection_rate\": {}, \"median_delay\": {}, \"delays\": [{}], "
              "\"median_abs_size_error\": {}}}",
              first_row ? "" : ",\n", controller, json_number(size), threshold,
              design ? "true" : "false", rates.false_alarms, json_number(rates.healthy_hours),
              json_number(rates.false_alarms_per_hour()), rates.leak_runs, rates.detected,
              json_number(rates.detection_rate()), json_number(rates.median_delay()),
              fmt::join(rates.delays, ", "), json_number(rates.median_abs_size_error()));
          first_row = false;
          if (design && size > 0.0) {
            f_md.print(
                "| {} | {} | {:.2g} | {:.3f} | {}/{} ({:.0f} %) | {} | {:.2f} ({:.1f}) | {} |\n",
                all[c].label, controller, size, size * kLitresPerMinutePerMPa, rates.detected,
                rates.leak_runs, 100.0 * rates.detection_rate(),
                std::isnan(rates.median_delay()) ? std::string("-")
                                                 : fmt::format("{:.1f}", rates.median_delay()),
                rates.false_alarms_per_hour(), rates.healthy_hours,
                rates.size_errors.empty()
                    ? std::string("-")
                    : fmt::format("{:.0f} %", 100.0 * rates.median_abs_size_error()));
          }
        }
      }
    }
    f_json.print("\n    ]}}{}\n", c + 1 < all.size() ? "," : "");
  }
  f_json.print("  ]\n}}\n");
  f_json.close();
  f_tsv.close();
  // How often the flow balance's 95 % interval at its first raise covers the true C_L.
  f_md.print(
      "\n| controller | C_L [m^3/(s Pa)] | raised within {:.0f} s | interval covers truth | "
      "median half-width / C_L |\n|---|---|---|---|---|\n",
      settings.detect_within);
  for (const auto& controller : controllers) {
    for (double size : settings.leak_sizes) {
      int raised = 0, covered = 0;
      std::vector<double> widths;
      for (const auto& r : results) {
        if (r.spec.leak != size || std::isnan(r.size_check.leak_coefficient)) continue;
        if (controller != "all" && sim::to_string(r.spec.scenario.controller) != controller) {
          continue;
        }
        ++raised;
        covered += r.size_check.covers(size) ? 1 : 0;
        widths.push_back(r.size_check.half_width / size);
      }
      std::sort(widths.begin(), widths.end());
      f_md.print("| {} | {:.2g} | {} | {}/{} | {} |\n", controller, size, raised, covered, raised,
                 widths.empty() ? std::string("-")
                                : fmt::format("{:.0f} %", 100.0 * widths[widths.size() / 2]));
      f_tsv_coverage.print("{}\t{:g}\t{}\t{}\t{:.4g}\n", controller, size, raised, covered,
                           widths.empty() ? NAN : widths[widths.size() / 2]);
    }
  }
  f_md.close();
  f_tsv_coverage.close();
  fmt::print("wrote {}/runs.json, summary.json, summary.tsv, summary.md, size_coverage.tsv\n",
             out.string());

  if (args.flag_set("plots")) {
    const std::string command =
        fmt::format("/usr/bin/python3 '{}' '{}'", args.get("plot-script"), out.string());
    if (std::system(command.c_str()) != 0) {
      throw std::runtime_error("plotting failed: " + command);
    }
  }
  return 0;
}

}  // namespace leakmon::cli
