#include "io/mqtt/mqtt_output.hpp"

#include <fmt/format.h>
#include <mosquitto.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <ctime>
#include <deque>
#include <filesystem>
#include <mutex>
#include <optional>
#include <system_error>
#include <thread>

#include "config/address.hpp"
#include "config/paths.hpp"
#include "io/event_json.hpp"

namespace leakmon::io::mqtt {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

using config::default_state_directory;
using config::resolve_path;

std::string readable_file(const config::ConfigNode& node, const config::ConfigNode& field,
                          bool directory) {
  const std::string path = resolve_path(node, field.as_string());
  std::error_code error;
  const bool exists = directory ? std::filesystem::is_directory(path, error)
                                : std::filesystem::is_regular_file(path, error);
  if (!exists || ::access(path.c_str(), R_OK) != 0) {
    field.fail(fmt::format("{} '{}' does not exist or is not readable",
                           directory ? "directory" : "file", path));
  }
  return path;
}

void check_topic(const config::ConfigNode& field, const std::string& topic) {
  if (topic.empty()) field.fail("the topic must not be empty (e.g. leakmon/SITE/RIG)");
  if (topic.find_first_of("+#") != std::string::npos)
    field.fail("the topic must not contain the wildcards + or #");
  if (topic.front() == '/' || topic.back() == '/')
    field.fail("the topic must not start or end with '/'");
  if (topic.find('\0') != std::string::npos) field.fail("the topic must not contain NUL");
}

}  // namespace

std::string topic_level(std::string_view name) {
  std::string out(name);
  for (char& c : out) {
    if (c == '/' || c == '+' || c == '#') c = '_';
  }
  return out.empty() ? "_" : out;
}

MqttSettings parse_mqtt_settings(const config::ConfigNode& node) {
  node.expect_keys({"name", "type", "host", "port", "topic", "client_id", "username", "password",
                    "password_file", "tls", "keepalive_s", "features_hz", "connect_timeout_s",
                    "reconnect_max_s", "queue"});
  MqttSettings s;
  s.name = node.get_string("name");
  s.host = node.has("host") ? config::read_host(node.at("host")) : "127.0.0.1";
  const auto topic = node.at("topic");
  s.topic = topic.as_string();
  check_topic(topic, s.topic);
  s.client_id = node.get_string("client_id", "leakmon-" + s.topic);
  for (char& c : s.client_id) {
    if (c == '/') c = '-';
  }
  if (s.client_id.empty() || s.client_id.size() > 65535)
    node.at("client_id").fail("the client id must have 1 to 65535 characters");
  s.username = node.get_string("username", "");
  if (auto password = node.find("password")) {
    if (s.username.empty()) password->fail("a password needs a username");
    if (node.has("password_file")) password->fail("give either password or password_file");
    s.password = password->as_string();
  }
  if (auto file = node.find("password_file")) {
    // Kept out of the configuration: a root-only file or a systemd credential (README.md).
    if (s.username.empty()) file->fail("a password needs a username");
    s.password = config::read_secret(*file);
  }
  if (auto tls = node.find("tls")) {
    tls->expect_keys({"ca_file", "ca_path", "cert_file", "key_file"});
    s.tls.enabled = true;
    if (auto f = tls->find("ca_file")) s.tls.ca_file = readable_file(node, *f, false);
    if (auto f = tls->find("ca_path")) s.tls.ca_path = readable_file(node, *f, true);
    if (s.tls.ca_file.empty() && s.tls.ca_path.empty())
      tls->fail("tls needs ca_file (the broker's CA certificate) or ca_path");
    const auto cert = tls->find("cert_file");
    const auto key = tls->find("key_file");
    if (cert.has_value() != key.has_value())
      (cert ? *cert : *key).fail("a client certificate needs both cert_file and key_file");
    if (cert) s.tls.cert_file = readable_file(node, *cert, false);
    if (key) s.tls.key_file = readable_file(node, *key, false);
  }
  s.port = static_cast<int>(node.get_int("port", s.tls.enabled ? 8883 : 1883, 1, 65535));
  s.keepalive_s = static_cast<int>(node.get_int("keepalive_s", 30, 5, 3600));
  s.features_hz = node.get_double("features_hz", 1.0, 0.0, 50.0);
  s.connect_timeout_s = node.get_double("connect_timeout_s", 10.0, 0.5, 300.0);
  s.reconnect_max_s = node.get_double("reconnect_max_s", 5.0, 0.5, 3600.0);
  s.queue_directory = default_state_directory() + "/mqtt-" + topic_level(s.name);
  if (auto queue = node.find("queue")) {
    queue->expect_keys({"directory", "max_events", "max_bytes"});
    if (auto directory = queue->find("directory")) {
      s.queue_directory = resolve_path(node, directory->as_string());
      if (s.queue_directory.empty()) directory->fail("the queue directory must not be empty");
    }
    s.queue_limits.max_events =
        static_cast<std::uint64_t>(queue->get_int("max_events", 10000, 1, 10'000'000));
    s.queue_limits.max_bytes =
        static_cast<std::uint64_t>(queue->get_int("max_bytes", 16ll << 20, 4096, 64ll << 30));
  }
  s.queue_limits.segment_bytes =
      std::clamp<std::uint64_t>(s.queue_limits.max_bytes / 8, 4096, 1u << 20);
  return s;
}

namespace {

void init_library_once() {
  // mosquitto_lib_init is not thread-safe; every output of the process shares one call.
  static std::once_flag once;
  std::call_once(once, [] { mosquitto_lib_init(); });
}

std::string error_text(int rc) {
  if (rc == MOSQ_ERR_ERRNO) return std::system_category().message(errno);
  return mosquitto_strerror(rc);
}

struct PendingEvent {
  std::string topic;
  std::string payload;
};

class MqttOutput final : public EventSink {
 public:
  explicit MqttOutput(MqttSettings settings)
      : settings_(std::move(settings)),
        status_topic_(settings_.topic + "/status"),
        event_topic_(settings_.topic + "/event") {}

  ~MqttOutput() override {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

  std::string_view name() const override { return settings_.name; }

  void publish(const Event& event) override {
    PendingEvent pending;
    pending.topic = event.actuator.empty()
                        ? event_topic_
                        : settings_.topic + "/" + topic_level(event.actuator) + "/event";
    pending.payload = to_json_line(event);
    {
      std::lock_guard lock(mutex_);
      if (handoff_.size() >= settings_.handoff_capacity) {
        events_dropped_.fetch_add(1, std::memory_order_relaxed);
        return;
      }
      handoff_.push_back(std::move(pending));
      ensure_started_locked();
    }
    wake_.notify_all();
  }

  void flush() override {
    std::lock_guard lock(mutex_);
    ensure_started_locked();
  }

  void attach_readings(ReadingSource source) override {
    {
      // Waits for a sampling in progress, so that a detached source is never called again.
      std::lock_guard readings_lock(readings_mutex_);
      readings_ = std::move(source);
    }
    std::lock_guard lock(mutex_);
    if (readings_) ensure_started_locked();
  }

  std::vector<SinkMetric> metrics() const override {
    auto load = [](const std::atomic<std::uint64_t>& v) {
      return static_cast<double>(v.load(std::memory_order_relaxed));
    };
    return {
        {"mqtt_connected", "1 while the output is connected to its MQTT broker", false,
         connected_.load(std::memory_order_relaxed) ? 1.0 : 0.0},
        {"mqtt_queue_events", "events waiting in the on-disk queue for the broker's PUBACK", false,
         load(queue_events_)},
        {"mqtt_queue_bytes", "bytes of the events waiting in the on-disk queue", false,
         load(queue_bytes_)},
        {"mqtt_queue_max_events", "the queue's bound in events", false,
         static_cast<double>(settings_.queue_limits.max_events)},
        {"mqtt_events_published_total", "events the broker acknowledged (PUBACK)", true,
         load(events_published_)},
        {"mqtt_events_dropped_total",
         "events not queued: the disk queue was full or could not be written", true,
         load(events_dropped_)},
        {"mqtt_features_published_total", "feature messages sent (QoS 0)", true,
         load(features_published_)},
        {"mqtt_features_dropped_total", "feature messages dropped while the broker was away", true,
         load(features_dropped_)},
        {"mqtt_connect_failures_total",
         "connection attempts that failed (unreachable, refused, TLS, credentials)", true,
         load(connect_failures_)},
    };
  }

 private:
  void ensure_started_locked() {
    if (!thread_.joinable() && !stopping_) thread_ = std::thread([this] { run(); });
  }

  // ---- the output's thread ------------------------------------------------------------------

  void run() {
    init_library_once();
    const auto feature_period = std::chrono::nanoseconds(
        static_cast<std::int64_t>(1e9 / std::max(settings_.features_hz, 1e-3)));
    auto next_features = Clock::now() + feature_period;  // the first connection has a moment
    while (true) {
      bool stopping = false;
      {
        std::unique_lock lock(mutex_);
        if (!mosq_) {
          wake_.wait_for(lock, 50ms, [&] { return stopping_ || !handoff_.empty(); });
        }
        stopping = stopping_;
      }
      store_handoff();
      if (stopping) break;
      if (!mosq_ && Clock::now() >= next_attempt_) connect();
      if (mosq_) service();
      if (connected_ && queue_ && mosq_) send_next_event();
      if (settings_.features_hz > 0 && Clock::now() >= next_features) {
        sample_features();
        next_features += feature_period;
        if (next_features < Clock::now()) next_features = Clock::now();
      }
      update_gauges();
    }
    shut_down();
  }

  // Moves the worker's events onto the disk queue (opening it first; another output instance,
  // e.g. the one a reload replaced, may still hold it for a moment).
  void store_handoff() {
    if (!queue_ && Clock::now() >= next_queue_attempt_) {
      try {
        queue_.emplace(settings_.queue_directory, settings_.queue_limits);
        if (queue_->recovered_truncated_bytes() > 0) {
          spdlog::warn("mqtt output {}: cut {} byte(s) of a torn record off the queue in {}",
                       settings_.name, queue_->recovered_truncated_bytes(),
                       settings_.queue_directory);
        }
        if (!queue_->empty()) {
          spdlog::info("mqtt output {}: {} event(s) queued earlier wait in {}", settings_.name,
                       queue_->events(), settings_.queue_directory);
        }
        queue_error_.clear();
      } catch (const DiskQueueBusy&) {
        next_queue_attempt_ = Clock::now() + 100ms;
      } catch (const std::exception& e) {
        if (queue_error_ != e.what()) {
          spdlog::error("mqtt output {}: cannot open the event queue: {}", settings_.name,
                        e.what());
          queue_error_ = e.what();
        }
        next_queue_attempt_ = Clock::now() + 5s;
      }
    }
    if (!queue_) return;
    std::deque<PendingEvent> batch;
    {
      std::lock_guard lock(mutex_);
      batch.swap(handoff_);
    }
    for (auto& event : batch) {
      bool stored = false;
      try {
        stored = queue_->append(event.topic, event.payload);
        if (!stored) report_queue_full();
      } catch (const std::exception& e) {
        spdlog::error("mqtt output {}: event not queued: {}", settings_.name, e.what());
      }
      if (!stored) events_dropped_.fetch_add(1, std::memory_order_relaxed);
    }
    if (queue_full_reported_ && queue_->events() < settings_.queue_limits.max_events / 2) {
      queue_full_reported_ = false;
    }
  }

  void report_queue_full() {
    if (queue_full_reported_) return;
    queue_full_reported_ = true;
    spdlog::error(
        "mqtt output {}: the event queue in {} is full ({} events, {} bytes; bound {} events, {} "
        "bytes): newer events are dropped (counted in leakmon_mqtt_events_dropped_total) until "
        "the broker takes the queued ones; the local event log keeps them all",
        settings_.name, settings_.queue_directory, queue_->events(), queue_->bytes(),
        settings_.queue_limits.max_events, settings_.queue_limits.max_bytes);
  }

  void connect() {
    attempt_started_ = Clock::now();
    mosq_ = mosquitto_new(settings_.client_id.c_str(), true, this);
    if (mosq_ == nullptr) {
      connection_failed("cannot create the MQTT client (out of memory)");
      return;
    }
    mosquitto_int_option(mosq_, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V311);
    mosquitto_connect_callback_set(mosq_, [](mosquitto*, void* self, int rc) {
      static_cast<MqttOutput*>(self)->on_connect(rc);
    });
    mosquitto_publish_callback_set(mosq_, [](mosquitto*, void* self, int mid) {
      static_cast<MqttOutput*>(self)->on_publish(mid);
    });
    mosquitto_log_callback_set(mosq_, [](mosquitto*, void* self, int level, const char* text) {
      if (level == MOSQ_LOG_ERR && text != nullptr)
        static_cast<MqttOutput*>(self)->library_error_ = text;
    });
    int rc = mosquitto_will_set(mosq_, status_topic_.c_str(), 7, "offline", 1, true);
    if (rc == MOSQ_ERR_SUCCESS && !settings_.username.empty()) {
      rc = mosquitto_username_pw_set(
          mosq_, settings_.username.c_str(),
          settings_.password.empty() ? nullptr : settings_.password.c_str());
    }
    if (rc == MOSQ_ERR_SUCCESS && settings_.tls.enabled) {
      auto c_str = [](const std::string& s) { return s.empty() ? nullptr : s.c_str(); };
      rc =
          mosquitto_tls_set(mosq_, c_str(settings_.tls.ca_file), c_str(settings_.tls.ca_path),
                            c_str(settings_.tls.cert_file), c_str(settings_.tls.key_file), nullptr);
      if (rc != MOSQ_ERR_SUCCESS) {
        connection_failed(fmt::format("TLS settings rejected: {}{}", error_text(rc),
                                      library_error_.empty() ? "" : ": " + library_error_));
        return;
      }
    }
    if (rc == MOSQ_ERR_SUCCESS) {
      library_error_.clear();
      rc = mosquitto_connect_async(mosq_, settings_.host.c_str(), settings_.port,
                                   settings_.keepalive_s);
    }
    if (rc != MOSQ_ERR_SUCCESS)
      connection_failed(fmt::format("cannot connect: {}", error_text(rc)));
  }

  void service() {
    const int rc = mosquitto_loop(mosq_, 50, 1);
    if (!mosq_) return;  // a callback gave up on this connection
    if (rc != MOSQ_ERR_SUCCESS) {
      std::string why = error_text(rc);
      if (!library_error_.empty()) why += ": " + library_error_;
      connection_failed(connected_ ? fmt::format("connection lost: {}", why)
                                   : fmt::format("cannot connect: {}", why));
      return;
    }
    if (birth_pending_) {
      birth_pending_ = false;
      const int birth =
          mosquitto_publish(mosq_, nullptr, status_topic_.c_str(), 6, "online", 1, true);
      if (birth != MOSQ_ERR_SUCCESS) {
        connection_failed(fmt::format("cannot publish the birth message: {}", error_text(birth)));
        return;
      }
    }
    if (!connected_ && Clock::now() - attempt_started_ >
                           std::chrono::duration<double>(settings_.connect_timeout_s)) {
      connection_failed(
          fmt::format("no answer (CONNACK) within {} s", settings_.connect_timeout_s));
    }
  }

  void on_connect(int rc) {
    if (rc != 0) {
      std::string why = mosquitto_connack_string(rc);
      if (rc == 4 || rc == 5) why += " (check username and password)";
      refused_ = fmt::format("the broker refused the connection: {}", why);
      return;  // the loop's next call fails on the closed connection; see service()
    }
    connected_ = true;
    backoff_ = 250ms;
    inflight_mid_.reset();
    // Published after the loop returns: libmosquitto holds its callback lock here, and
    // publishing under it inverts the library's lock order.
    birth_pending_ = true;
    if (!last_error_.empty() || !ever_connected_) {
      spdlog::info("mqtt output {}: connected to {}:{} as {}, publishing under {}/", settings_.name,
                   settings_.host, settings_.port, settings_.client_id, settings_.topic);
    }
    ever_connected_ = true;
    last_error_.clear();
  }

  void on_publish(int mid) {
    if (offline_mid_ && *offline_mid_ == mid) offline_mid_.reset();
    if (!inflight_mid_ || *inflight_mid_ != mid || !queue_) return;
    inflight_mid_.reset();
    try {
      queue_->pop_front();
      events_published_.fetch_add(1, std::memory_order_relaxed);
    } catch (const std::exception& e) {
      // The broker has it; the queue could not record that, so it may go out again later.
      spdlog::error("mqtt output {}: {}", settings_.name, e.what());
    }
  }

  void send_next_event() {
    // A broker that took the connection but never acknowledges (overloaded, stuck) is left
    // like a lost one: reconnect and publish the head again.
    if (inflight_mid_ &&
        Clock::now() - inflight_since_ > std::chrono::seconds(settings_.keepalive_s)) {
      connection_failed(fmt::format("no PUBACK within {} s", settings_.keepalive_s));
      return;
    }
    if (inflight_mid_ || queue_->empty()) return;
    const QueuedMessage& next = queue_->front();
    int mid = 0;
    const int rc =
        mosquitto_publish(mosq_, &mid, next.topic.c_str(), static_cast<int>(next.payload.size()),
                          next.payload.data(), 1, false);
    if (rc == MOSQ_ERR_SUCCESS) {
      inflight_mid_ = mid;
      inflight_since_ = Clock::now();
    } else {
      connection_failed(fmt::format("cannot publish: {}", error_text(rc)));
    }
  }

  void sample_features() {
    std::vector<ActuatorReading> readings;
    {
      std::lock_guard lock(readings_mutex_);
      if (!readings_) return;
      readings = readings_();
    }
    // A socket that still holds unsent data means a slow broker: features wait for no one.
    if (!connected_ || mosquitto_want_write(mosq_)) {
      features_dropped_.fetch_add(readings.size(), std::memory_order_relaxed);
      return;
    }
    for (const auto& r : readings) {
      const std::string& payload = r.message;
      const std::string topic = settings_.topic + "/" + topic_level(r.actuator) + "/features";
      const int rc = mosquitto_publish(mosq_, nullptr, topic.c_str(),
                                       static_cast<int>(payload.size()), payload.data(), 0, false);
      if (rc == MOSQ_ERR_SUCCESS) {
        features_published_.fetch_add(1, std::memory_order_relaxed);
      } else {
        features_dropped_.fetch_add(1, std::memory_order_relaxed);
      }
    }
  }

  void connection_failed(const std::string& why_in) {
    const std::string why = refused_.empty() ? why_in : refused_;
    refused_.clear();
    if (!connected_) connect_failures_.fetch_add(1, std::memory_order_relaxed);
    if (why != last_error_) {
      spdlog::error("mqtt output {}: broker {}:{}{}: {}; retrying (events wait on disk in {})",
                    settings_.name, settings_.host, settings_.port,
                    settings_.tls.enabled ? " (TLS)" : "", why, settings_.queue_directory);
      last_error_ = why;
    }
    drop_connection();
    next_attempt_ = Clock::now() + backoff_;
    backoff_ = std::min<std::chrono::nanoseconds>(
        backoff_ * 2, std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::duration<double>(settings_.reconnect_max_s)));
  }

  // A fresh client per attempt: nothing half-sent survives in the library, the queue's head is
  // simply published again (at least once, in order).
  void drop_connection() {
    if (mosq_ != nullptr) mosquitto_destroy(mosq_);
    mosq_ = nullptr;
    connected_ = false;
    birth_pending_ = false;
    inflight_mid_.reset();
  }

  void shut_down() {
    // Events handed over but not yet on disk: another instance (the one a reload replaced) may
    // hold the queue for a moment; they are written before this output goes.
    const auto give_up = Clock::now() + 2s;
    while (!queue_ && Clock::now() < give_up) {
      bool waiting = false;
      {
        std::lock_guard lock(mutex_);
        waiting = !handoff_.empty();
      }
      if (!waiting) break;
      next_queue_attempt_ = Clock::now();
      store_handoff();
      if (!queue_) std::this_thread::sleep_for(50ms);
    }
    {
      std::lock_guard lock(mutex_);
      if (!handoff_.empty()) {
        spdlog::error("mqtt output {}: {} event(s) could not be queued in {} and are lost to MQTT",
                      settings_.name, handoff_.size(), settings_.queue_directory);
        events_dropped_.fetch_add(handoff_.size(), std::memory_order_relaxed);
        handoff_.clear();
      }
    }
    if (mosq_ != nullptr && connected_) {
      // A clean stop says so itself (a clean DISCONNECT suppresses the will), and waits briefly
      // for the event in flight.
      int mid = 0;
      if (mosquitto_publish(mosq_, &mid, status_topic_.c_str(), 7, "offline", 1, true) ==
          MOSQ_ERR_SUCCESS) {
        offline_mid_ = mid;
        const auto deadline = Clock::now() + 1s;
        while (mosq_ && (offline_mid_ || inflight_mid_) && Clock::now() < deadline) {
          if (mosquitto_loop(mosq_, 50, 1) != MOSQ_ERR_SUCCESS) break;
        }
      }
      if (mosq_) mosquitto_disconnect(mosq_);
      if (mosq_) mosquitto_loop(mosq_, 50, 1);
    }
    drop_connection();
    update_gauges();
    queue_.reset();
  }

  void update_gauges() {
    if (queue_) {
      queue_events_.store(queue_->events(), std::memory_order_relaxed);
      queue_bytes_.store(queue_->bytes(), std::memory_order_relaxed);
    }
  }

  MqttSettings settings_;
  const std::string status_topic_;
  const std::string event_topic_;

  // Shared with the worker (publish) and the daemon.
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<PendingEvent> handoff_;
  bool stopping_ = false;
  std::thread thread_;
  std::mutex readings_mutex_;
  ReadingSource readings_;

  // Read by the metrics thread.
  std::atomic<bool> connected_{false};
  std::atomic<std::uint64_t> queue_events_{0};
  std::atomic<std::uint64_t> queue_bytes_{0};
  std::atomic<std::uint64_t> events_published_{0};
  std::atomic<std::uint64_t> events_dropped_{0};
  std::atomic<std::uint64_t> features_published_{0};
  std::atomic<std::uint64_t> features_dropped_{0};
  std::atomic<std::uint64_t> connect_failures_{0};

  // The output's thread only.
  std::optional<DiskQueue> queue_;
  std::string queue_error_;
  bool queue_full_reported_ = false;
  Clock::time_point next_queue_attempt_{};
  mosquitto* mosq_ = nullptr;
  Clock::time_point attempt_started_{};
  Clock::time_point next_attempt_{};
  std::chrono::nanoseconds backoff_ = 250ms;
  std::optional<int> inflight_mid_;
  Clock::time_point inflight_since_{};
  std::optional<int> offline_mid_;
  std::string last_error_;
  std::string refused_;
  std::string library_error_;
  bool ever_connected_ = false;
  bool birth_pending_ = false;
};

}  // namespace

std::unique_ptr<EventSink> make_mqtt_output_with(MqttSettings settings) {
  return std::make_unique<MqttOutput>(std::move(settings));
}

std::unique_ptr<EventSink> make_mqtt_output(const config::ConfigNode& node) {
  return make_mqtt_output_with(parse_mqtt_settings(node));
}

}  // namespace leakmon::io::mqtt
