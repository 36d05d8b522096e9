// The live page's data side: the trend history keeps a fixed number of points in the memory
// docs/daemon.md states, the sampling path (worker status -> snapshot -> history) allocates
// nothing once warm, /api/trend and /api/events answer what was recorded, and /ack asks for
// the configured token. The page in a browser: live_page_test.py.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <fmt/format.h>

#include "daemon/config.hpp"
#include "pipeline/replay.hpp"
#include "pipeline/worker.hpp"
#include "realtime/acquisition_loop.hpp"
#include "realtime/spsc_ring.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/http_request.hpp"
#include "tests/support/paths.hpp"
#include "views/operator_view.hpp"

namespace leakmon::views {
namespace {

using test::request;

ServiceSnapshot snapshot_of(const std::string& actuator, double score, pipeline::AlarmState state) {
  ServiceSnapshot s;
  pipeline::ActuatorStatus a;
  a.name = actuator;
  a.score = score;
  a.raise_threshold = 1.0;
  a.state = state;
  a.leak_coefficient = 2.5e-12;  // 0.15 l/min/MPa
  a.channels.push_back({"p1", io::DeviceStatus::ok, detect::SensorFault::none, 0});
  a.channels.push_back({"p2", io::DeviceStatus::failure, detect::SensorFault::frozen, 0});
  s.actuators.push_back(a);
  GroupSnapshot g;
  g.name = "main";
  s.groups.push_back(g);
  return s;
}

TEST(TrendHistory, KeepsTheNewestPointsInFixedMemory) {
  TrendHistory history(100, {"cyl"}, {"main"});
  EXPECT_EQ(history.memory_bytes(), 100 * (sizeof(TrendPoint) + sizeof(LoopPoint)));
  ServiceSnapshot snapshot = snapshot_of("cyl", 0.0, pipeline::AlarmState::normal);
  {
    test::AllocationScope scope;
    for (int i = 0; i < 250; ++i) {
      snapshot.actuators[0].score = i;
      snapshot.groups[0].wakeup_latency.count = static_cast<std::uint64_t>(i) * 10;
      snapshot.groups[0].wakeup_latency.sum_ns = static_cast<std::int64_t>(i) * 10 * 5000;
      history.record(1000.0 + i, snapshot);
    }
    EXPECT_EQ(scope.count(), 0u) << "recording allocated";
  }
  const auto* series = history.actuator("cyl");
  ASSERT_NE(series, nullptr);
  ASSERT_EQ(series->points.size(), 100u);
  EXPECT_DOUBLE_EQ(series->points[0].unix_time, 1150.0);
  EXPECT_DOUBLE_EQ(series->points[0].score, 150.0);
  EXPECT_DOUBLE_EQ(series->points[99].unix_time, 1249.0);
  EXPECT_NEAR(series->points[99].leak_lpm_per_mpa, 0.15, 1e-12);
  EXPECT_EQ(series->points[99].channel_status[1],
            static_cast<std::uint8_t>(io::DeviceStatus::failure));
  EXPECT_EQ(series->points[99].channel_status[2], TrendPoint::kNoChannel);
  const auto* loop = history.group("main");
  ASSERT_NE(loop, nullptr);
  EXPECT_NEAR(loop->points[99].latency_mean_us, 5.0, 1e-9) << "mean over the interval";
  EXPECT_EQ(history.memory_bytes(), 100 * (sizeof(TrendPoint) + sizeof(LoopPoint)));
}

// docs/daemon.md "Live page": 4 h at 1 s is 14400 points, 1.4 MB per actuator and 0.5 MB per
// sampling group. A change of TrendPoint or LoopPoint that breaks this must update the docs.
TEST(TrendHistory, DefaultMemoryIsWhatTheDocumentationStates) {
  const pipeline::MetricsConfig defaults;
  const std::size_t capacity = trend_capacity(defaults.trend_seconds, defaults.trend_interval_s);
  EXPECT_EQ(capacity, 14400u);
  EXPECT_LE(TrendHistory::memory_bytes(capacity, 1, 0), 1'400'000u);
  EXPECT_LE(TrendHistory::memory_bytes(capacity, 0, 1), 500'000u);
  TrendHistory history(capacity, {"a", "b"}, {"main"});
  EXPECT_LE(history.memory_bytes(), 2 * 1'400'000u + 500'000u);
}

TEST(TrendHistory, AnActuatorAddedByAReloadGetsItsRing) {
  TrendHistory history(10, {"a"}, {"main"});
  history.record(1.0, snapshot_of("b", 1.0, pipeline::AlarmState::normal));
  ASSERT_NE(history.actuator("b"), nullptr);
  EXPECT_EQ(history.actuator("b")->points.size(), 1u);
  EXPECT_EQ(history.actuator("a")->points.size(), 0u);
}

// The daemon's sampling path on a real worker fed with a simulated rig: once the snapshot has
// held every actuator's status, sampling allocates nothing.
TEST(OperatorView, SamplingTheWorkerAllocatesNothing) {
  sim::Scenario scenario = sim::preset("healthy", 3);
  scenario.duration_s = 12.0;
  const capture::Capture capture = sim::simulate(scenario);
  pipeline::DaemonConfig config = pipeline::default_replay_config(capture);
  config.actuators[0].name = "cylinder";
  const std::string driver = config.actuators[0].channels[capture::Role::p1].driver;
  std::vector<pipeline::ChannelRef> channels;
  std::vector<const std::vector<double>*> columns;
  for (const char* role : {"p1", "p2", "u", "x", "xref"}) {
    channels.push_back({driver, role, std::nullopt});
    columns.push_back(&capture.column(role));
  }
  realtime::SpscRing<realtime::Sample> ring(4096);
  std::vector<io::EventSink*> no_sinks;
  pipeline::Worker worker(config, {pipeline::GroupInput{"main", &ring, channels, 2'000'000}},
                          no_sinks);
  realtime::LoopCounters counters;  // an idle loop's, as the daemon reads them

  OperatorView view(config, {"main"});
  view.set_source([&](ServiceSnapshot& out) {
    worker.status_into(out.actuators);
    out.groups.resize(1);
    read_group(out.groups[0], "main", counters, ring.capacity(), false, 0);
    out.samples_processed = worker.samples_processed();
  });
  std::size_t row = 0;
  auto feed = [&](double seconds) {
    for (const std::size_t end = row + static_cast<std::size_t>(seconds * 500); row < end; ++row) {
      realtime::Sample sample;
      sample.tick = row;
      sample.t = capture.column("t")[row];
      sample.channel_count = static_cast<std::uint32_t>(columns.size());
      for (std::size_t k = 0; k < columns.size(); ++k) sample.values[k] = (*columns[k])[row];
      ASSERT_TRUE(ring.try_push(sample));
      if (ring.size() > 1000) worker.drain(0);
    }
    worker.drain(0);
  };
  feed(4.0);
  view.sample(1.0);  // warm: both snapshots the view swaps between take their shape
  view.sample(2.0);
  std::uint64_t allocations = 0;
  for (int i = 0; i < 20; ++i) {
    feed(0.3);  // the worker may allocate (events); the sampling must not
    test::AllocationScope scope;
    view.sample(3.0 + i);
    allocations += scope.count();
  }
  EXPECT_EQ(allocations, 0u);

  // What was sampled is what /api/trend answers, from `since` on.
  const std::string all = view.trend_json(0.0);
  EXPECT_NE(all.find("\"name\":\"cylinder\""), std::string::npos);
  EXPECT_NE(all.find("\"time\":[1,2,3,"), std::string::npos) << all.substr(0, 400);
  const std::string recent = view.trend_json(21.5);
  EXPECT_NE(recent.find("\"time\":[22]"), std::string::npos) << recent.substr(0, 400);
  EXPECT_NE(recent.find("\"sensors\":[{\"channel\":\"p1\",\"status\":\"ok\",\"fault\":null"),
            std::string::npos);
  const auto response = view.handle(request("GET", "/api/trend?since=21.5"));
  ASSERT_TRUE(response.has_value());
  EXPECT_EQ(response->status, 200);
  EXPECT_EQ(response->content_type.rfind("application/json", 0), 0u);
  EXPECT_EQ(view.handle(request("GET", "/api/trend?since=yesterday"))->status, 400);
}

// The sampler thread writes while HTTP readers read (run under TSan: label `threads`).
TEST(OperatorView, SamplerThreadAndReadersShareTheHistorySafely) {
  pipeline::DaemonConfig config;
  config.metrics.trend_interval_s = 0.01;
  config.metrics.trend_seconds = 60.0;
  std::atomic<int> calls{0};
  {
    OperatorView view(config, {"main"});
    auto sink = view.event_sink();
    view.start_sampling([&](ServiceSnapshot& out) {
      if (out.actuators.empty()) out = snapshot_of("cyl", 0.5, pipeline::AlarmState::normal);
      out.actuators[0].score = calls.fetch_add(1);
    });
    std::thread publisher([&] {
      for (int i = 0; i < 200; ++i) {
        io::Event event;
        event.kind = io::EventKind::overrun;
        sink->publish(event);
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    });
    std::size_t answers = 0;
    while (calls.load() < 20) {
      answers += view.handle(request("GET", "/api/trend?since=0"))->body.size() > 0 ? 1 : 0;
      answers += view.handle(request("GET", "/api/events?after=3"))->body.size() > 0 ? 1 : 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    publisher.join();
    EXPECT_GT(answers, 0u);
    const std::string trend = view.trend_json(0.0);
    EXPECT_NE(trend.find("\"name\":\"cyl\""), std::string::npos);
  }  // the view stops its sampler
  const int after_stop = calls.load();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(calls.load(), after_stop) << "the sampler outlived the view";
}

// What a browser loads when it opens the page on a full default history (4 h at 1 s): the
// size of the first /api/trend answer, printed with the time it took (not asserted).
TEST(OperatorView, FullDefaultHistoryAnswer) {
  pipeline::DaemonConfig config;
  pipeline::ActuatorConfig actuator;
  actuator.name = "cyl";
  config.actuators.push_back(actuator);
  OperatorView view(config, {"main"});
  ServiceSnapshot source = snapshot_of("cyl", 0.5, pipeline::AlarmState::normal);
  int i = 0;
  view.set_source([&](ServiceSnapshot& out) {
    source.actuators[0].score = 0.3 + 1e-4 * (i % 1000);
    source.actuators[0].index_p1 = 21345.678 + i % 977;
    source.actuators[0].index_p2 = 23456.789 + i % 911;
    source.actuators[0].p1 = 6.5e6 + 1234.5 * (i % 100);
    source.actuators[0].p2 = 10.8e6 - 1234.5 * (i % 100);
    out = source;
  });
  const std::size_t capacity = trend_capacity(config.metrics.trend_seconds, 1.0);
  for (; i < static_cast<int>(capacity) + 10; ++i) view.sample(1.8e9 + i);
  const auto start = std::chrono::steady_clock::now();
  const std::string json = view.trend_json(0.0);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("full history: %zu points, /api/trend?since=0 is %.2f MB, built in %.1f ms\n",
              capacity, static_cast<double>(json.size()) / 1e6, ms);
  EXPECT_NE(json.find("\"time\":[1800000010,"), std::string::npos) << "oldest points dropped";
  EXPECT_NE(json.find(fmt::format("{}]", 1.8e9 + capacity + 9)), std::string::npos);
  EXPECT_LT(json.size(), 5'000'000u);
}

TEST(OperatorView, ServesThePageAndItsAssetsFromTheBinary) {
  pipeline::DaemonConfig config;
  const OperatorView view(config, {});
  for (const char* path : {"/", "/index.html", "/live.js", "/live.css", "/uplot.min.js",
                           "/uplot.min.css", "/favicon.svg"}) {
    const auto response = view.handle({"GET", path, ""});
    ASSERT_TRUE(response.has_value()) << path;
    EXPECT_EQ(response->status, 200) << path;
    EXPECT_GT(response->body.size(), 100u) << path;
  }
  const std::string page = view.handle(request("GET", "/"))->body;
  EXPECT_NE(page.find("Content-Security-Policy"), std::string::npos);
  EXPECT_EQ(page.find("http://"), std::string::npos) << "no external URL";
  EXPECT_EQ(page.find("https://"), std::string::npos) << "no external URL";
  EXPECT_FALSE(view.handle(request("GET", "/metrics")).has_value()) << "the daemon's own route";
  EXPECT_FALSE(view.handle(request("GET", "/nothing")).has_value());
}

TEST(OperatorView, RecentEventsKeepTheNewestInOrder) {
  pipeline::DaemonConfig config;
  const OperatorView view(config, {});
  auto sink = view.event_sink();
  for (int i = 0; i < 130; ++i) {
    io::Event event;
    event.kind = io::EventKind::overrun;
    event.message = "n";  // then appended: GCC 12 -O3 takes "n" + std::string for an overlap
    event.message += std::to_string(i);
    sink->publish(event);
  }
  const std::string all = view.handle(request("GET", "/api/events"))->body;
  EXPECT_EQ(all.rfind("{\"next\":131,", 0), 0u) << all.substr(0, 40);
  EXPECT_EQ(all.find("\"n29\""), std::string::npos) << "older than the newest 100";
  EXPECT_NE(all.find("{\"seq\":31,\"event\":{"), std::string::npos);
  const std::string after = view.handle(request("GET", "/api/events?after=129"))->body;
  EXPECT_EQ(after.find("\"n128\""), std::string::npos);
  EXPECT_NE(after.find("\"n129\""), std::string::npos);
}

// A restart keeps what the page has seen: the trend survives as text, exactly (NaN too), and a
// file that is not one is refused with the line and field named.
TEST(TrendHistory, TrendTextRoundTripsAndBadFilesNameTheirFault) {
  TrendHistory history(50, {"cyl"}, {"main"});
  ServiceSnapshot snapshot = snapshot_of("cyl", 0.25, pipeline::AlarmState::active_unacknowledged);
  snapshot.actuators[0].index_p1 = 21345.678912;
  snapshot.actuators[0].oil_temperature = NAN;
  for (int i = 0; i < 5; ++i) history.record(1.8e9 + i, snapshot);
  const std::string text = encode_trend(history.actuator("cyl")->points);
  const std::vector<TrendPoint> back = decode_trend(text);
  ASSERT_EQ(back.size(), 5u);
  EXPECT_DOUBLE_EQ(back[4].unix_time, 1.8e9 + 4);
  EXPECT_DOUBLE_EQ(back[4].index_p1, 21345.678912);
  EXPECT_DOUBLE_EQ(back[4].score, 0.25);
  EXPECT_TRUE(std::isnan(back[4].oil_temperature));
  EXPECT_EQ(back[4].alarm, static_cast<std::uint8_t>(pipeline::AlarmState::active_unacknowledged));
  EXPECT_EQ(back[4].channel_status[1], static_cast<std::uint8_t>(io::DeviceStatus::failure));
  EXPECT_EQ(back[4].channel_status[2], TrendPoint::kNoChannel);

  const auto error_of = [](const std::string& bad) -> std::string {
    try {
      decode_trend(bad);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "(accepted)";
  };
  const std::size_t header_end = text.find('\n', text.find('\n') + 1) + 1;
  const std::string header = text.substr(0, header_end);
  const std::string row = text.substr(header_end, text.find('\n', header_end) + 1 - header_end);
  EXPECT_NE(error_of("hello\n").find("line 1: not a leakmon trend file"), std::string::npos);
  EXPECT_NE(error_of("# leakmon trend 2\n").find("format version 2"), std::string::npos);
  EXPECT_NE(error_of(header + "1,2,3\n").find("line 3: 3 fields, expected 16"), std::string::npos);
  std::string bad_number = row;
  bad_number.replace(bad_number.find(','), 1, ",x");
  EXPECT_NE(error_of(header + bad_number).find("line 3, field index_p1: 'x"), std::string::npos)
      << error_of(header + bad_number);
  EXPECT_NE(error_of(header + row + row).find("line 4, field unix_time: not after"),
            std::string::npos);
  std::string bad_alarm = row;
  const std::size_t alarm_at = [&] {
    std::size_t at = 0;
    for (int k = 0; k < 10; ++k) at = bad_alarm.find(',', at) + 1;
    return at;
  }();
  bad_alarm.replace(alarm_at, 1, "7");
  EXPECT_NE(error_of(header + bad_alarm).find("field alarm: 7 is not an integer 0..3"),
            std::string::npos)
      << error_of(header + bad_alarm);
  EXPECT_EQ(error_of(header), "(accepted)") << "an empty history is a valid one";
}

TEST(OperatorView, TrendAndEventsSurviveARestart) {
  const std::string dir = test::scratch_dir("OperatorView.TrendAndEventsSurviveARestart");
  const pipeline::StateStore store(dir + "/state");
  pipeline::DaemonConfig config;
  pipeline::ActuatorConfig actuator;
  actuator.name = "cyl 1";  // a name that is not a file name as it is
  config.actuators.push_back(actuator);
  config.metrics.trend_interval_s = 1.0;
  config.metrics.trend_seconds = 100.0;
  const double before_stop = 1.8e9 + 1000.0;
  {
    OperatorView view(config, {"main"});
    ServiceSnapshot source = snapshot_of("cyl 1", 0.5, pipeline::AlarmState::normal);
    int i = 0;
    view.set_source([&](ServiceSnapshot& out) {
      source.actuators[0].score = 0.01 * i;
      out = source;
    });
    for (; i < 150; ++i) view.sample(before_stop - 149 + i);  // keeps the newest 100
    view.save_history(store);
  }
  ASSERT_TRUE(std::filesystem::exists(store.trend_file_of("cyl 1")));

  std::ofstream(dir + "/events.jsonl")
      << "{\"event\": \"daemon_started\", \"version\": \"0.1.0\"}\n"
      << "{\"t\": 12.5, \"event\": \"alarm_raised\", \"actuator\": \"cyl 1\"}\n"
      << "not json\n"
      << "{\"event\": \"daemon_stopped\", \"reas";  // a crash mid-line

  // Restarted 30 s later: points older than the history's 100 s are dropped, a gap point
  // breaks the line over the downtime, and the page's events start with the log's.
  OperatorView view(config, {"main"});
  EXPECT_TRUE(view.restore_history(store, before_stop + 30.0).empty());
  EXPECT_EQ(view.restore_events(dir + "/events.jsonl"), 2u);
  view.set_source([](ServiceSnapshot& out) {
    out = snapshot_of("cyl 1", 0.125, pipeline::AlarmState::normal);
  });
  view.sample(before_stop + 30.0);
  const std::string trend = view.trend_json(0.0);
  EXPECT_NE(trend.find(fmt::format("\"time\":[{},", before_stop - 70)), std::string::npos)
      << trend.substr(0, 300);
  EXPECT_NE(trend.find(fmt::format("{},{},{}]", before_stop, before_stop + 1, before_stop + 30)),
            std::string::npos)
      << "the newest point, the gap, the first after the restart";
  EXPECT_NE(trend.find(fmt::format("\"score\":[{},", 0.01 * 79)), std::string::npos)
      << "oldest kept: i = 79";
  EXPECT_NE(trend.find(fmt::format("{},null,0.125]", 0.01 * 149)), std::string::npos)
      << "newest, gap, restarted";
  const std::string events = view.handle(request("GET", "/api/events"))->body;
  EXPECT_EQ(events.rfind("{\"next\":3,", 0), 0u) << events;
  EXPECT_NE(events.find("\"alarm_raised\""), std::string::npos);
  EXPECT_EQ(events.find("daemon_stopped"), std::string::npos) << "the torn line is skipped";

  // A file that is not a trend is set aside with a warning naming it, never half-read.
  std::ofstream(store.trend_file_of("cyl 1")) << "# leakmon trend 1\ngarbage\n";
  OperatorView fresh(config, {"main"});
  const auto warnings = fresh.restore_history(store, before_stop + 30.0);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find(store.trend_file_of("cyl 1").string()), std::string::npos);
  EXPECT_NE(warnings[0].find("line 2: unexpected columns"), std::string::npos) << warnings[0];
}

TEST(OperatorView, TellsThePageWhetherAckNeedsAToken) {
  pipeline::DaemonConfig config;
  OperatorView open_view(config, {});
  EXPECT_NE(open_view.trend_json(0.0).find("\"ack_token_required\":false"), std::string::npos);
  EXPECT_FALSE(open_view.handle(request("POST", "/ack?actuator=cyl")).has_value())
      << "the service's route: the service checks the token (tests/daemon/routes_test.cpp)";
  config.metrics.ack_token = "s3cret-token-0123456789";
  OperatorView view(config, {});
  EXPECT_NE(view.trend_json(0.0).find("\"ack_token_required\":true"), std::string::npos);
  view.set_ack_token_required(false);
  EXPECT_NE(view.trend_json(0.0).find("\"ack_token_required\":false"), std::string::npos);
}

std::string metrics_config(const std::string& metrics) {
  return "drivers: [{name: rig, type: sim, scenario: healthy}]\n"
         "actuators: [{name: a, channels: {p1: p1}}]\n"
         "metrics: " +
         metrics + "\n";
}

TEST(OperatorViewConfig, ANonLoopbackAddressNeedsAToken) {
  const auto local = daemon::parse_config(config::ConfigNode::load_string(
      metrics_config("{address: 127.0.0.1, port: 9187}"), "local.yaml"));
  EXPECT_TRUE(local.metrics.ack_token.empty());
  try {
    daemon::parse_config(config::ConfigNode::load_string(
        metrics_config("{address: 0.0.0.0, port: 9187}"), "open.yaml"));
    FAIL() << "0.0.0.0 without a token was accepted";
  } catch (const config::ConfigError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("open.yaml:3:"), std::string::npos) << message;
    EXPECT_NE(message.find("metrics.address"), std::string::npos) << message;
    EXPECT_NE(message.find("ack_token"), std::string::npos) << message;
  }
  EXPECT_THROW(daemon::parse_config(config::ConfigNode::load_string(
                   metrics_config("{address: 0.0.0.0, ack_token: short}"), "short.yaml")),
               config::ConfigError);
  const auto shared = daemon::parse_config(config::ConfigNode::load_string(
      metrics_config("{address: 0.0.0.0, ack_token: 0123456789abcdef, trend_seconds: 600, "
                     "trend_interval_s: 0.5}"),
      "shared.yaml"));
  EXPECT_EQ(shared.metrics.ack_token, "0123456789abcdef");
  EXPECT_EQ(trend_capacity(shared.metrics.trend_seconds, shared.metrics.trend_interval_s), 1200u);
  EXPECT_THROW(daemon::parse_config(config::ConfigNode::load_string(
                   metrics_config("{trend_seconds: 604800, trend_interval_s: 0.1}"), "big.yaml")),
               config::ConfigError);
  EXPECT_TRUE(daemon::is_loopback_address("127.0.0.1"));
  EXPECT_TRUE(daemon::is_loopback_address("127.1.2.3"));
  EXPECT_FALSE(daemon::is_loopback_address("0.0.0.0"));
  EXPECT_FALSE(daemon::is_loopback_address("192.168.1.5"));
}

}  // namespace
}  // namespace leakmon::views
