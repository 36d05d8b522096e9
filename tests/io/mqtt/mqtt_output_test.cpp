// The MQTT output in-process, with threads the way the daemon drives it: the worker publishing,
// the metrics thread reading counters, the output's thread sampling live readings; against
// Debian's mosquitto. Also the bounded queue's refusal, counted, when the broker is away.
#include "io/mqtt/mqtt_output.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>

#include "tests/io/mqtt/mosquitto_peers.hpp"

namespace leakmon::io::mqtt {
namespace {

using namespace std::chrono_literals;

double metric(const EventSink& sink, std::string_view name) {
  for (const auto& m : sink.metrics())
    if (m.name == name) return m.value;
  return -1.0;
}

MqttSettings settings_for(const std::string& dir, int port) {
  MqttSettings s;
  s.name = "fleet";
  s.port = port;
  s.topic = "leakmon/test/inproc";
  s.client_id = "leakmon-inproc-" + std::to_string(port);
  s.features_hz = 20;
  s.connect_timeout_s = 1;
  s.reconnect_max_s = 0.5;
  s.queue_directory = dir + "/queue";
  return s;
}

TEST(MqttOutput, DeliversEveryEventInOrderWhileOtherThreadsReadAndSample) {
  const std::string dir = test::scratch_dir("mqtt_output_threads");
  test::Broker broker(dir, test::free_port());
  test::Subscriber subscriber(broker.port(), dir + "/received.txt", "leakmon-test-inproc");
  // Declared before the output, so destroyed after it: its thread samples until it is gone.
  std::atomic<int> samplings{0};
  auto sink = make_mqtt_output_with(settings_for(dir, broker.port()));
  sink->attach_readings([&samplings] {
    ++samplings;
    // The message as the daemon formats it from its snapshot (views/status_json.hpp
    // features_json); the output only carries it.
    ActuatorReading reading;
    reading.actuator = "cyl/1";
    reading.message =
        R"({"t": 1.5, "actuator": "cyl/1", "index_p1_pa": 21500, "score": 0.5, )"
        R"("leak_lpm_per_mpa": 0.12, "leak_lpm_per_mpa_ci95": 0.01, "alarm_state": "normal", )"
        R"("learning": false, "index": 21.5, "unix_time": 1800000000.5})";
    return std::vector<ActuatorReading>{reading};
  });
  constexpr int kEvents = 200;
  std::atomic<bool> done{false};
  std::thread metrics_reader([&] {
    while (!done) {
      (void)sink->metrics();
      std::this_thread::sleep_for(1ms);
    }
  });
  const auto start = std::chrono::steady_clock::now();
  std::chrono::nanoseconds publishing{0};  // the worker's time inside publish()
  std::thread worker([&] {
    for (int i = 0; i < kEvents; ++i) {
      Event event;
      event.kind = i % 2 == 0 ? EventKind::driver_fault : EventKind::alarm_raised;
      event.actuator = i % 2 == 0 ? "" : "cyl/1";
      event.message = std::to_string(i);
      const auto before = std::chrono::steady_clock::now();
      sink->publish(event);
      publishing += std::chrono::steady_clock::now() - before;
      if (i % 50 == 0) sink->flush();
    }
  });
  worker.join();
  const bool all = test::eventually(
      [&] { return subscriber.messages("/event").size() >= static_cast<std::size_t>(kEvents); },
      30s);
  const auto delivered = std::chrono::steady_clock::now() - start;
  done = true;
  metrics_reader.join();
  // Measurements for docs/performance.md, not assertions.
  std::printf("%d events: publish() %.1f us mean on the worker; all delivered after %.0f ms\n",
              kEvents, std::chrono::duration<double, std::micro>(publishing).count() / kEvents,
              std::chrono::duration<double, std::milli>(delivered).count());
  ASSERT_TRUE(all) << subscriber.messages("/event").size();
  const auto events = subscriber.messages("/event");
  ASSERT_EQ(events.size(), static_cast<std::size_t>(kEvents));
  for (int i = 0; i < kEvents; ++i) {
    EXPECT_NE(events[i].second.find("\"message\": \"" + std::to_string(i) + "\""),
              std::string::npos)
        << i << ": " << events[i].second;
    EXPECT_EQ(events[i].first,
              i % 2 == 0 ? "leakmon/test/inproc/event" : "leakmon/test/inproc/cyl_1/event");
  }
  EXPECT_TRUE(test::eventually([&] { return metric(*sink, "mqtt_queue_events") == 0.0; }, 5s));
  EXPECT_EQ(metric(*sink, "mqtt_events_published_total"), kEvents);
  EXPECT_EQ(metric(*sink, "mqtt_connected"), 1.0);

  ASSERT_TRUE(test::eventually([&] { return !subscriber.messages("/features").empty(); }, 10s));
  const auto feature = subscriber.messages("/features").back();
  EXPECT_EQ(feature.first, "leakmon/test/inproc/cyl_1/features");
  EXPECT_NE(feature.second.find("\"index_p1_pa\": 21500, "), std::string::npos) << feature.second;
  EXPECT_NE(feature.second.find("\"index\": 21.5"), std::string::npos) << feature.second;
  EXPECT_NE(feature.second.find("\"leak_lpm_per_mpa\": 0.12"), std::string::npos);
  EXPECT_NE(feature.second.find("\"leak_lpm_per_mpa_ci95\": 0.01"), std::string::npos);

  // Detached: never sampled again.
  sink->attach_readings({});
  const int sampled = samplings;
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(samplings, sampled);

  // A clean stop says "offline" itself (a clean disconnect suppresses the will).
  sink.reset();
  EXPECT_EQ(test::retained_status(broker.port(), "leakmon/test/inproc"), "offline");
}

TEST(MqttOutput, AFullQueueRefusesNewerEventsAndCountsThem) {
  const std::string dir = test::scratch_dir("mqtt_output_full");
  MqttSettings settings = settings_for(dir, test::free_port());  // no broker there
  settings.queue_limits.max_events = 5;
  auto sink = make_mqtt_output_with(settings);
  for (int i = 0; i < 20; ++i) {
    Event event;
    event.kind = EventKind::overrun;
    event.message = std::to_string(i);
    sink->publish(event);
  }
  EXPECT_TRUE(test::eventually(
      [&] {
        return metric(*sink, "mqtt_queue_events") == 5.0 &&
               metric(*sink, "mqtt_events_dropped_total") == 15.0;
      },
      10s))
      << metric(*sink, "mqtt_queue_events") << " " << metric(*sink, "mqtt_events_dropped_total");
  EXPECT_EQ(metric(*sink, "mqtt_connected"), 0.0);
  EXPECT_GE(metric(*sink, "mqtt_connect_failures_total"), 1.0);
  sink.reset();
  // The oldest five stay for the next start.
  DiskQueue queue(dir + "/queue", {});
  ASSERT_EQ(queue.events(), 5u);
  EXPECT_NE(queue.front().payload.find("\"message\": \"0\""), std::string::npos);
}

}  // namespace
}  // namespace leakmon::io::mqtt
