// Every view formats the one snapshot the service fills (views/snapshot.hpp), with the one
// vocabulary (views/vocabulary.hpp): /metrics, /status and its human form, the live page's
// /api/trend and the MQTT feature message, each from the same hand-filled snapshot and without a
// daemon. The same quantity has the same name and value in every JSON view, and every renamed
// field is still there under its old name for one release.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "capture/units.hpp"
#include "pipeline/config.hpp"
#include "views/json_writer.hpp"
#include "views/metrics_text.hpp"
#include "views/operator_view.hpp"
#include "views/snapshot.hpp"
#include "views/status_json.hpp"
#include "views/vocabulary.hpp"

namespace leakmon::views {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

ServiceSnapshot hand_filled() {
  ServiceSnapshot s;
  s.unix_time = 1800000100.25;
  s.version = "9.8.7";
  s.config = "/etc/leakmon/rig \"A\".yaml";
  s.uptime_s = 100.5;
  s.reload = {false, 2, 1, 1800000000};
  s.cpu_latency_request_held = true;
  s.samples_processed = 50250;
  s.events = 7;
  s.decision_latency.count = 4;
  s.decision_latency.sum_ns = 400'000;
  s.decision_latency.max_ns = 150'000;
  s.decision_latency.p99_ns = 150'000;
  s.decision_latency.below = {0, 0, 0, 1, 4, 4, 4, 4, 4, 4, 4};

  GroupSnapshot g;
  g.name = "main";
  g.realtime = true;
  g.cycles = 50000;
  g.overruns = 3;
  g.missed_cycles = 5;
  g.ring_drops = 1;
  g.ring_high_water = 17;
  g.ring_capacity = 8192;
  g.last_cycle_age_s = 0.0015;
  g.wakeup_latency.count = 50000;
  g.wakeup_latency.sum_ns = 1'425'000'000;  // 28.5 us mean
  g.wakeup_latency.max_ns = 423'700;
  g.wakeup_latency.p99_ns = 61'000;
  g.wakeup_latency.below = {100,   2000,  49000, 49900, 49990, 49999,
                            50000, 50000, 50000, 50000, 50000};
  s.groups.push_back(g);

  DriverSnapshot d;
  d.name = "rig";
  d.health.status = io::DeviceStatus::function_check;
  d.health.detail = "connecting";
  d.health.last_error = "connection refused";
  d.health.errors = 4;
  d.health.reconnects = 2;
  s.drivers.push_back(d);

  s.output_metrics.push_back({"fleet", {"mqtt_connected", "1 while connected", false, 1.0}});
  s.http = {12, 1, 0, 2};

  pipeline::ActuatorStatus a;
  a.name = "cyl 1";
  a.alarm = "internal_leakage";
  a.detector = "flow_balance";
  a.state = pipeline::AlarmState::active_unacknowledged;
  a.learning = false;
  a.learning_seconds_left = 0.0;
  a.raise_threshold = 1.0;
  a.clear_threshold = 0.5;
  a.t = 61.998;
  a.index_p1 = 25849.3;
  a.index_p2 = kNaN;  // p1 only
  a.score = 1.97;
  a.baseline = kNaN;
  a.leak_coefficient = 2.5e-12;     // 0.15 l/min/MPa
  a.leak_coefficient_ci = 1.0e-13;  // 0.006
  a.oil_temperature = 41.5;
  a.p1 = 6.5e6;
  a.p2 = 10.8e6;
  a.decisions = 1545;
  a.gap_samples = 3;
  a.repeated_samples = 0;
  a.mode_visibility = kNaN;
  a.channels.push_back({"p1", io::DeviceStatus::ok, detect::SensorFault::none, 2});
  a.channels.push_back({"p2", io::DeviceStatus::failure, detect::SensorFault::frozen, 0});
  a.relearns = 1;
  a.judged = true;
  a.not_judged_reason = detect::NotJudgedReason::none;
  a.judged_seconds = 45.0;
  a.decided_seconds = 60.0;
  a.learned_state_saved_unix = 1800000040.25;  // 60 s before the fill
  s.actuators.push_back(a);

  pipeline::ActuatorStatus b;
  b.name = "press";
  b.alarm = "internal_leakage";
  b.detector = "detail_xcorr";
  b.learning = true;
  b.learning_seconds_left = 22.3;
  b.index_p1 = 31000.0;
  b.index_p2 = 29000.0;
  b.not_judged_reason = detect::NotJudgedReason::learning;
  b.not_judged_since = 0.04;
  s.actuators.push_back(b);
  return s;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

bool has_line(const std::string& text, const std::string& line) {
  for (const auto& l : lines_of(text)) {
    if (l == line) return true;
  }
  return false;
}

// The JSON text of a node (yaml-cpp reads JSON), for comparing one value across documents.
std::string text_of(const YAML::Node& node) {
  YAML::Emitter out;
  out.SetMapFormat(YAML::Flow);
  out.SetSeqFormat(YAML::Flow);
  out << node;
  return out.c_str();
}

TEST(SnapshotViews, MetricsFromTheSnapshot) {
  const std::string text = metrics_text(hand_filled());
  EXPECT_TRUE(has_line(text, R"(leakmon_build_info{version="9.8.7"} 1)")) << text;
  EXPECT_TRUE(has_line(text, R"(leakmon_index_pascal{actuator="cyl 1",channel="p1"} 25849.3)"));
  EXPECT_EQ(text.find(R"(leakmon_index_pascal{actuator="cyl 1",channel="p2"})"), std::string::npos)
      << "no p2 index where p2 is not acquired";
  EXPECT_TRUE(has_line(text, R"(leakmon_index_pascal{actuator="press",channel="p2"} 29000)"));
  // The alarm's ISA-18.2 state under its name, and under the old label name for one release.
  EXPECT_TRUE(has_line(text,
                       R"(leakmon_alarm_active{actuator="cyl 1",alarm="internal_leakage",)"
                       R"(alarm_state="active_unacknowledged",state="active_unacknowledged"} 1)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_leak_lpm_per_mpa{actuator="cyl 1"} )" +
                                 metric_number(units::lpm_per_mpa(2.5e-12))))
      << text;
  EXPECT_TRUE(has_line(text, R"(leakmon_leak_lpm_per_mpa{actuator="press"} NaN)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_oil_temperature_celsius{actuator="cyl 1"} 41.5)"));
  EXPECT_EQ(text.find(R"(leakmon_oil_temperature_celsius{actuator="press"})"), std::string::npos);
  EXPECT_TRUE(has_line(text, R"(leakmon_learned_state_age_seconds{actuator="cyl 1"} 60)"));
  EXPECT_EQ(text.find(R"(leakmon_learned_state_age_seconds{actuator="press"})"), std::string::npos);
  EXPECT_TRUE(
      has_line(text, R"(leakmon_sensor_status{actuator="cyl 1",channel="p2",status="failure"} 1)"));
  EXPECT_TRUE(has_line(
      text, R"(leakmon_driver_up{driver="rig",detail="connecting",state="connecting"} 0)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_driver_status{driver="rig",status="function_check"} 1)"));
  EXPECT_TRUE(has_line(
      text, R"(leakmon_loop_wakeup_latency_seconds_bucket{group="main",le="5e-05"} 49000)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_loop_wakeup_latency_seconds_sum{group="main"} 1.425)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_decision_latency_seconds_bucket{le="0.0002"} 4)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_decision_latency_seconds_count{} 4)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_mqtt_connected{output="fleet"} 1)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_config_reload_success 0)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_config_last_reload_timestamp_seconds 1800000000)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_cpu_wakeup_latency_request_held 1)"));
  EXPECT_TRUE(has_line(text, R"(leakmon_http_connections 2)"));
  // Each family is declared once: one HELP and one TYPE line per name.
  std::vector<std::string> helped;
  for (const auto& line : lines_of(text)) {
    if (line.rfind("# HELP ", 0) != 0) continue;
    const std::string name = line.substr(7, line.find(' ', 7) - 7);
    EXPECT_EQ(std::count(helped.begin(), helped.end(), name), 0) << name;
    helped.push_back(name);
  }
  EXPECT_GE(helped.size(), 40u);
}

TEST(SnapshotViews, StatusFromTheSnapshotInTheOneVocabulary) {
  const YAML::Node doc = YAML::Load(status_json(hand_filled()));
  EXPECT_EQ(doc["version"].as<std::string>(), "9.8.7");
  EXPECT_EQ(doc["config"].as<std::string>(), "/etc/leakmon/rig \"A\".yaml");
  EXPECT_FALSE(doc["reload"]["ok"].as<bool>());
  EXPECT_EQ(doc["samples_processed"].as<int>(), 50250);
  EXPECT_DOUBLE_EQ(doc["decision_latency_p99_us"].as<double>(), 150.0);
  const YAML::Node g = doc["groups"][0];
  EXPECT_DOUBLE_EQ(g["wakeup_latency_mean_us"].as<double>(), 28.5);
  EXPECT_DOUBLE_EQ(g["wakeup_latency_max_us"].as<double>(), 423.7);
  EXPECT_DOUBLE_EQ(g["wakeup_latency_us"]["mean"].as<double>(), 28.5) << "renamed, kept";
  const YAML::Node d = doc["drivers"][0];
  EXPECT_EQ(d["status"].as<std::string>(), "function_check");
  EXPECT_EQ(d["detail"].as<std::string>(), "connecting");
  EXPECT_EQ(d["last_error"].as<std::string>(), "connection refused");
  const YAML::Node a = doc["actuators"][0];
  EXPECT_EQ(a["name"].as<std::string>(), "cyl 1");
  EXPECT_EQ(a["state"].as<std::string>(), "alarm");
  EXPECT_EQ(a["alarm"].as<std::string>(), "internal_leakage");
  EXPECT_EQ(a["alarm_state"].as<std::string>(), "active_unacknowledged");
  EXPECT_TRUE(a["learning_seconds_left"].IsNull()) << "not learning";
  EXPECT_DOUBLE_EQ(a["index_p1_pa"].as<double>(), 25849.3);
  EXPECT_TRUE(a["index_p2_pa"].IsNull());
  EXPECT_DOUBLE_EQ(a["leak_lpm_per_mpa"].as<double>(), 0.15);
  EXPECT_NEAR(a["leak_lpm_per_mpa_ci95"].as<double>(), 0.006, 1e-12);
  EXPECT_DOUBLE_EQ(a["p2_pa"].as<double>(), 10.8e6);
  EXPECT_DOUBLE_EQ(a["oil_temperature_c"].as<double>(), 41.5);
  EXPECT_TRUE(a["sensors"][0]["fault"].IsNull());
  EXPECT_EQ(a["sensors"][1]["fault"].as<std::string>(), "frozen");
  EXPECT_EQ(a["sensors"][1]["status"].as<std::string>(), "failure");
  // Renamed, kept for one release.
  EXPECT_DOUBLE_EQ(a["index_pa"]["p1"].as<double>(), 25849.3);
  EXPECT_DOUBLE_EQ(a["threshold"]["raise"].as<double>(), 1.0);
  EXPECT_EQ(a["alarms"][0]["state"].as<std::string>(), "active_unacknowledged");
  const YAML::Node b = doc["actuators"][1];
  EXPECT_EQ(b["state"].as<std::string>(), "learning");
  EXPECT_DOUBLE_EQ(b["learning_seconds_left"].as<double>(), 22.3);
  EXPECT_TRUE(b["leak_lpm_per_mpa"].IsNull()) << "null, never NaN";
  // Judging: `cyl 1` judges, 45 of 60 s; `press` does not, since it started learning.
  EXPECT_TRUE(a["judged"].as<bool>());
  EXPECT_TRUE(a["not_judged_reason"].IsNull());
  EXPECT_TRUE(a["not_judged_since"].IsNull());
  EXPECT_DOUBLE_EQ(a["judged_share"].as<double>(), 0.75);
  EXPECT_FALSE(b["judged"].as<bool>());
  EXPECT_EQ(b["not_judged_reason"].as<std::string>(), "learning");
  EXPECT_DOUBLE_EQ(b["not_judged_since"].as<double>(), 0.04);
  EXPECT_TRUE(b["judged_share"].IsNull()) << "nothing decided yet";
}

// `leakmon status` names a detector that does not judge outside learning (issue 23).
TEST(SnapshotViews, StatusTextSaysWhenADetectorDoesNotJudge) {
  ServiceSnapshot s = hand_filled();
  s.actuators[0].state = pipeline::AlarmState::normal;
  s.actuators[0].judged = false;
  s.actuators[0].not_judged_reason = detect::NotJudgedReason::in_motion;
  s.actuators[0].not_judged_since = 601.2;
  const std::string text = status_text_from_json(status_json(s));
  EXPECT_NE(text.find("  NOT JUDGING: in_motion since t 601.2 s (judged 75 % of the time)"),
            std::string::npos)
      << text;
  // Learning has its own line.
  EXPECT_EQ(text.find("NOT JUDGING: learning"), std::string::npos) << text;
}

TEST(SnapshotViews, StatusTextReadsThisAndThePreviousVocabulary) {
  const std::string text = status_text_from_json(status_json(hand_filled()));
  EXPECT_NE(text.find("leakmon 9.8.7 running 100 s"), std::string::npos) << text;
  EXPECT_NE(text.find("last reload: REJECTED"), std::string::npos) << text;
  EXPECT_NE(text.find("wake-up latency avg 28.5 us max 423.7 us"), std::string::npos) << text;
  EXPECT_NE(text.find("actuator cyl 1: ALARM, detector flow_balance"), std::string::npos) << text;
  EXPECT_NE(text.find("  alarm internal_leakage: active_unacknowledged"), std::string::npos);
  EXPECT_NE(text.find("index p1 25.85 kPa, p2 n/a; score 1.97 (raises at 1, clears at 0.5)"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("leak estimate 0.150 +/- 0.006 l/min/MPa"), std::string::npos) << text;
  EXPECT_NE(text.find("channel p2: failure frozen"), std::string::npos) << text;
  EXPECT_NE(text.find("actuator press: learning, 23 s left"), std::string::npos) << text;
  EXPECT_EQ(text.find("nan"), std::string::npos) << text;
}

TEST(SnapshotViews, FeatureMessageFromTheSnapshot) {
  const ServiceSnapshot s = hand_filled();
  const std::string message = features_json(s, s.actuators[0]);
  EXPECT_EQ(message,
            fmt::format(R"({{"t": 61.998, "actuator": "cyl 1", "index_p1_pa": 25849.3, )"
                        R"("score": 1.97, "leak_lpm_per_mpa": {}, "leak_lpm_per_mpa_ci95": {}, )"
                        R"("alarm_state": "active_unacknowledged", "learning": false, )"
                        R"("judged": true, "index": {}, "unix_time": 1800000100.25}})",
                        units::lpm_per_mpa(2.5e-12), units::lpm_per_mpa(1.0e-13), 25849.3 / 1e3));
  // What is not known yet is left out, as in the events.
  const std::string learning = features_json(s, s.actuators[1]);
  EXPECT_EQ(learning.find("score"), std::string::npos) << learning;
  EXPECT_EQ(learning.find("leak_lpm_per_mpa"), std::string::npos) << learning;
  EXPECT_NE(learning.find(R"("index": 31)"), std::string::npos) << learning;
  EXPECT_NE(learning.find(R"("judged": false, "not_judged_reason": "learning")"), std::string::npos)
      << learning;
}

// The human form from a document as the previous release wrote it (`leakmon status` of this
// release against a daemon not yet restarted), with values not known yet.
TEST(SnapshotViews, StatusTextOfThePreviousReleasesDocument) {
  const std::string json =
      R"({"version":"0.1.0","uptime_s":12.4,"config":"demo.yaml","reload":{"ok":true},)"
      R"("groups":[{"name":"main","cycles":6000,"overruns":0,"missed_cycles":0,"ring_drops":0,)"
      R"("ring_high_water":3,"ring_capacity":8192,"realtime":false,)"
      R"("wakeup_latency_us":{"mean":null,"max":null},"ended":false}],)"
      R"("drivers":[{"name":"rig","status":"ok","detail":"ok","last_error":null,"errors":0}],)"
      R"("actuators":[{"name":"cyl","detector":"flow_balance","state":"learning",)"
      R"("learning_seconds_left":22.3,"t":12.0,"index_pa":{"p1":25000,"p2":null},"score":null,)"
      R"("threshold":{"raise":1,"clear":0.5},"baseline_pa":null,)"
      R"("leak_lpm_per_mpa":{"estimate":null,"ci95":null},"oil_temperature_c":null,)"
      R"("alarms":[{"name":"internal_leakage","state":"normal"}],"suspended":false,)"
      R"("sensors":[{"channel":"p2","status":"ok","fault":null,"spikes_rejected":0}]}]})";
  const std::string text = status_text_from_json(json);
  EXPECT_EQ(text.find("nan"), std::string::npos) << text;
  EXPECT_NE(text.find("learning, 23 s left"), std::string::npos) << text;
  EXPECT_NE(text.find("p2 n/a"), std::string::npos) << text;
  EXPECT_NE(text.find("leak estimate n/a"), std::string::npos) << text;
  EXPECT_NE(text.find("channel p2: ok"), std::string::npos) << text;
  EXPECT_THROW(status_text_from_json("not json {"), std::runtime_error);
  EXPECT_THROW(status_text_from_json("{\"x\":1}"), std::runtime_error);
}

// /status and the page's /api/trend write every field of the vocabulary, with the same value.
TEST(SnapshotViews, StatusAndPageShareEveryFieldAndValue) {
  const ServiceSnapshot snapshot = hand_filled();
  pipeline::DaemonConfig config;
  config.metrics.ack_token = "0123456789abcdef";
  OperatorView page(config, {"main"});
  page.set_source([&](ServiceSnapshot& out) { out = snapshot; });
  page.sample(1800000100.0);
  page.sample(1800000101.0);
  const YAML::Node trend = YAML::Load(page.trend_json(0.0));
  const YAML::Node status = YAML::Load(status_json(snapshot));
  EXPECT_TRUE(trend["ack_token_required"].as<bool>());
  for (const char* key : {"version", "uptime_s", "config", "reload", "samples_processed", "events",
                          "decision_latency_p99_us"}) {
    EXPECT_EQ(text_of(trend[key]), text_of(status[key])) << key;
  }
  for (std::size_t i = 0; i < snapshot.actuators.size(); ++i) {
    const YAML::Node p = trend["actuators"][i];
    const YAML::Node s = status["actuators"][i];
    for (const auto& field : actuator_fields()) {
      const std::string key(field.name);
      ASSERT_TRUE(p[key]) << key << " missing on the page";
      ASSERT_TRUE(s[key]) << key << " missing in /status";
      EXPECT_EQ(text_of(p[key]), text_of(s[key])) << key;
    }
    EXPECT_EQ(text_of(p["sensors"]), text_of(s["sensors"]));
  }
  for (const auto& field : group_fields()) {
    const std::string key(field.name);
    EXPECT_EQ(text_of(trend["groups"][0][key]), text_of(status["groups"][0][key])) << key;
  }
  EXPECT_EQ(text_of(trend["drivers"]), text_of(status["drivers"]));

  // The page's trend columns, each under its name and, renamed, under its old name too.
  const YAML::Node columns = trend["actuators"][0]["trend"];
  EXPECT_EQ(columns["time"].size(), 2u);
  EXPECT_DOUBLE_EQ(columns["index_p1_pa"][1].as<double>(), 25849.3);
  EXPECT_EQ(columns["alarm_state_code"][1].as<int>(), 1);
  EXPECT_TRUE(columns["index_p2_pa"][1].IsNull());
  for (const auto& renamed : renamed_fields()) {
    if (renamed.where != "/api/trend columns") continue;
    std::string old_name(renamed.old_name);
    const YAML::Node* table = &columns;
    const YAML::Node loop = trend["groups"][0]["trend"];
    if (old_name.rfind("groups[].", 0) == 0) {
      old_name = old_name.substr(9);
      table = &loop;
    }
    ASSERT_TRUE((*table)[old_name]) << old_name;
    EXPECT_EQ(text_of((*table)[old_name]), text_of((*table)[std::string(renamed.name)]))
        << old_name;
  }
}

// Every renamed field of the JSON views is still written under its old name, with the value of
// its new one (docs/daemon.md "Vocabulary" lists them from the same table).
TEST(SnapshotViews, RenamedFieldsKeepTheirOldNameForOneRelease) {
  const ServiceSnapshot snapshot = hand_filled();
  pipeline::DaemonConfig config;
  OperatorView page(config, {"main"});
  page.set_source([&](ServiceSnapshot& out) { out = snapshot; });
  page.sample(1800000100.0);
  const YAML::Node trend = YAML::Load(page.trend_json(0.0));
  const YAML::Node status = YAML::Load(status_json(snapshot));
  const YAML::Node features = YAML::Load(features_json(snapshot, snapshot.actuators[0]));
  // `a.b` is a member of a member; `list[].x` a member of the first element.
  auto find = [](YAML::Node node, std::string path) {
    while (!path.empty()) {
      const std::size_t dot = path.find('.');
      std::string step = path.substr(0, dot);
      path = dot == std::string::npos ? "" : path.substr(dot + 1);
      const bool list = step.size() > 2 && step.substr(step.size() - 2) == "[]";
      if (list) step.resize(step.size() - 2);
      // reset(): yaml-cpp's operator= would write into the document, not rebind.
      node.reset(node[step]);
      if (list && node) node.reset(node[0]);
      if (!node) return node;
    }
    return node;
  };
  int checked = 0;
  for (const auto& renamed : renamed_fields()) {
    const std::string old_name(renamed.old_name);
    YAML::Node root;
    if (renamed.where == "/status") {
      root.reset(old_name.rfind("groups", 0) == 0 ? status : status["actuators"][0]);
    } else if (renamed.where == "/api/trend") {
      root.reset(old_name.rfind("groups", 0) == 0 ? trend : trend["actuators"][0]);
    } else if (renamed.where == "mqtt features") {
      root.reset(features);
    } else {
      continue;  // the trend columns above; /metrics labels in MetricsFromTheSnapshot
    }
    EXPECT_TRUE(find(root, old_name)) << renamed.where << " " << old_name;
    ++checked;
  }
  EXPECT_GE(checked, 15);
  EXPECT_DOUBLE_EQ(features["index"].as<double>(), features["index_p1_pa"].as<double>() / 1e3);
  // The one name that changed its meaning: the page's `state` is the actuator's state now, as in
  // /status; the alarm's ISA-18.2 state is `alarm_state` everywhere.
  EXPECT_EQ(trend["actuators"][0]["state"].as<std::string>(), "alarm");
  EXPECT_EQ(trend["actuators"][0]["alarm_state"].as<std::string>(), "active_unacknowledged");
  EXPECT_EQ(trend["actuators"][0]["channels"][0]["fault"].as<std::string>(), "none")
      << "the old `channels` keep their old form";
}

}  // namespace
}  // namespace leakmon::views
