#include "views/operator_view.hpp"

#include <fmt/format.h>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <span>
#include <sstream>
#include <utility>

#include "config/yaml_reader.hpp"
#include "pipeline/event_log.hpp"
#include "views/json_writer.hpp"
#include "views/vocabulary.hpp"
#include "views/web_assets.hpp"

namespace leakmon::views {
namespace {

// The wall time to the millisecond, the resolution the trend file keeps (trend_history.cpp).
double unix_now_ms() {
  const double now =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  return std::round(now * 1e3) / 1e3;
}

// The first point of `ring` newer than `since` (points are in time order).
template <typename Ring>
std::size_t first_after(const Ring& ring, double since) {
  std::size_t lo = 0, hi = ring.size();
  while (lo < hi) {
    const std::size_t mid = (lo + hi) / 2;
    if (ring[mid].unix_time > since) {
      hi = mid;
    } else {
      lo = mid + 1;
    }
  }
  return lo;
}

http::HttpResponse json_response(std::string body) {
  return {200, "application/json; charset=utf-8", std::move(body)};
}

http::HttpResponse bad_request(std::string body) {
  return {400, "text/plain; charset=utf-8", std::move(body)};
}

// A trend column: the value of `column` of each of the ring's points after `from`.
template <typename Ring, typename Column>
void write_column(JsonWriter& json, std::string_view name, const Ring& ring, std::size_t from,
                  const Column& column) {
  json.begin_array(name);
  for (std::size_t i = from; i < ring.size(); ++i) write_value(json, {}, column, ring[i]);
  json.end_array();
}

template <typename Ring>
void write_time_column(JsonWriter& json, const Ring& ring, std::size_t from) {
  json.begin_array("time");
  for (std::size_t i = from; i < ring.size(); ++i) json.number({}, ring[i].unix_time);
  json.end_array();
}

// The column of `table` named `name` (renamed columns repeat it under their old name).
template <typename Row>
const Field<Row>& column_named(std::span<const Field<Row>> table, std::string_view name) {
  for (const auto& field : table) {
    if (field.name == name) return field;
  }
  throw std::logic_error("views/vocabulary: no trend column named " + std::string(name));
}

// The "trend" member of one actuator or group: null before its first point, else the time
// column, every column of `columns` and, for one release, the renamed columns under their old
// names ({old name, name}).
template <typename Series, typename Row>
void write_trend(JsonWriter& json, const Series* series, double since,
                 std::span<const Field<Row>> columns,
                 std::initializer_list<std::pair<const char*, const char*>> renamed) {
  if (series == nullptr) {
    json.null("trend");
    return;
  }
  const auto& ring = series->points;
  const std::size_t from = first_after(ring, since);
  json.begin_object("trend");
  write_time_column(json, ring, from);
  for (const auto& column : columns) write_column(json, column.name, ring, from, column);
  for (const auto& [old_name, name] : renamed) {
    write_column(json, old_name, ring, from, column_named(columns, name));
  }
  json.end_object();
}

}  // namespace

void RecentEvents::add(const io::Event& event) {
  std::string line = to_json_line(event);
  std::lock_guard lock(mutex_);
  lines_.emplace_back(next_++, std::move(line));
  while (lines_.size() > capacity_) lines_.pop_front();
}

void RecentEvents::add_line(std::string line) {
  std::lock_guard lock(mutex_);
  lines_.emplace_back(next_++, std::move(line));
  while (lines_.size() > capacity_) lines_.pop_front();
}

std::string RecentEvents::json_after(std::uint64_t after) const {
  std::lock_guard lock(mutex_);
  std::string out = fmt::format("{{\"next\":{},\"events\":[", next_);
  bool first = true;
  for (const auto& [seq, line] : lines_) {
    if (seq <= after) continue;
    fmt::format_to(std::back_inserter(out), "{}{{\"seq\":{},\"event\":{}}}", first ? "" : ",", seq,
                   line);
    first = false;
  }
  out += "]}";
  return out;
}

namespace {

// Forwards the worker's events into the shared ring; outlives the view if the sinks do.
class RecentEventsSink final : public io::EventSink {
 public:
  explicit RecentEventsSink(std::shared_ptr<RecentEvents> events) : events_(std::move(events)) {}
  void publish(const io::Event& event) override { events_->add(event); }

 private:
  std::shared_ptr<RecentEvents> events_;
};

std::vector<std::string> actuator_names(const pipeline::DaemonConfig& config) {
  std::vector<std::string> names;
  for (const auto& a : config.actuators) names.push_back(a.name);
  return names;
}

}  // namespace

OperatorView::OperatorView(const pipeline::DaemonConfig& config,
                           const std::vector<std::string>& groups)
    : interval_s_(config.metrics.trend_interval_s),
      events_(std::make_shared<RecentEvents>(kRecentEvents)),
      history_(trend_capacity(config.metrics.trend_seconds, config.metrics.trend_interval_s),
               actuator_names(config), groups),
      ack_token_required_(!config.metrics.ack_token.empty()) {}

OperatorView::~OperatorView() {
  {
    std::lock_guard lock(stop_mutex_);
    stop_ = true;
  }
  stop_signal_.notify_all();
  if (sampler_.joinable()) sampler_.join();
}

std::unique_ptr<io::EventSink> OperatorView::event_sink() const {
  return std::make_unique<RecentEventsSink>(events_);
}

void OperatorView::set_source(SnapshotSource source) { source_ = std::move(source); }

void OperatorView::start_sampling(SnapshotSource source) {
  set_source(std::move(source));
  sample(unix_now_ms());  // the page has a point at once
  sampler_ = std::thread([this] { run_sampler(); });
}

void OperatorView::run_sampler() {
  const auto interval = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(interval_s_));
  auto next = std::chrono::steady_clock::now() + interval;
  std::unique_lock lock(stop_mutex_);
  while (!stop_signal_.wait_until(lock, next, [this] { return stop_; })) {
    lock.unlock();
    sample(unix_now_ms());
    lock.lock();
    next += interval;
    // After a stall (suspend, debugger) start afresh instead of catching up in a burst.
    if (next < std::chrono::steady_clock::now()) next = std::chrono::steady_clock::now() + interval;
  }
}

void OperatorView::sample(double unix_time) {
  if (!source_) return;
  source_(scratch_);
  std::lock_guard lock(mutex_);
  history_.record(unix_time, scratch_);
  // Swapping keeps both snapshots' storage: the next fill reuses what `latest_` held.
  std::swap(latest_, scratch_);
  latest_time_ = unix_time;
}

void OperatorView::set_ack_token_required(bool required) {
  std::lock_guard lock(mutex_);
  ack_token_required_ = required;
}

void OperatorView::save_history(const pipeline::StateStore& store) const {
  std::vector<std::pair<std::string, std::string>> files;
  {
    std::lock_guard lock(mutex_);
    for (const auto& series : history_.actuators()) {
      if (series.points.size() > 0) files.emplace_back(series.name, encode_trend(series.points));
    }
  }
  for (const auto& [actuator, text] : files)
    store.write_atomically(store.trend_file_of(actuator), text);
}

std::vector<std::string> OperatorView::restore_history(const pipeline::StateStore& store,
                                                       double unix_now) {
  std::vector<std::string> warnings;
  const double oldest = unix_now - static_cast<double>(history_.capacity()) * interval_s_;
  std::vector<std::string> names;
  {
    std::lock_guard lock(mutex_);
    for (const auto& series : history_.actuators()) names.push_back(series.name);
  }
  for (const auto& name : names) {
    const std::filesystem::path path = store.trend_file_of(name);
    std::error_code error;
    if (!std::filesystem::exists(path, error)) continue;
    std::ifstream in(path, std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    std::vector<TrendPoint> points;
    try {
      if (!in) throw std::runtime_error("cannot be read");
      points = decode_trend(text.str());
    } catch (const std::exception& e) {
      warnings.push_back(fmt::format("{}: trend history set aside: {}", path.string(), e.what()));
      continue;
    }
    std::erase_if(points, [&](const TrendPoint& p) {
      return !(p.unix_time >= oldest && p.unix_time < unix_now);
    });
    if (points.empty()) continue;
    // A point of nothing where the daemon was down, so the page breaks its lines there instead
    // of drawing a straight one across the downtime.
    TrendPoint gap;
    gap.unix_time =
        std::min(points.back().unix_time + interval_s_, 0.5 * (points.back().unix_time + unix_now));
    for (double* value :
         {&gap.index_p1, &gap.index_p2, &gap.score, &gap.raise_threshold, &gap.leak_lpm_per_mpa,
          &gap.leak_lpm_per_mpa_ci95, &gap.p1, &gap.p2, &gap.oil_temperature}) {
      *value = std::numeric_limits<double>::quiet_NaN();
    }
    gap.channel_status.fill(TrendPoint::kNoChannel);
    points.push_back(gap);
    std::lock_guard lock(mutex_);
    history_.restore(name, points);
  }
  return warnings;
}

std::size_t OperatorView::restore_events(const std::string& event_log) {
  std::ifstream in(event_log, std::ios::binary);
  if (!in) return 0;
  // Only the tail: a log of months must not be read whole to show a hundred lines.
  constexpr std::streamoff kTail = 256 * 1024;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(size > kTail ? size - kTail : 0);
  std::string line;
  if (size > kTail) std::getline(in, line);  // most likely the second half of a line
  std::deque<std::string> newest;
  while (std::getline(in, line)) {
    if (line.size() < 2 || line.front() != '{' || line.back() != '}') continue;
    bool valid = true;
    for (std::size_t i = 0; i < line.size() && valid;) {
      unsigned code = 0;
      const std::size_t length = config::utf8_sequence(line, i, code);
      valid = length > 0 && code >= 0x20;
      i += std::max<std::size_t>(length, 1);
    }
    if (!valid) continue;
    try {
      if (!YAML::Load(line).IsMap()) continue;
    } catch (const YAML::Exception&) {
      continue;
    }
    newest.push_back(std::move(line));
    if (newest.size() > kRecentEvents) newest.pop_front();
  }
  for (auto& kept : newest) events_->add_line(std::move(kept));
  return newest.size();
}

std::size_t OperatorView::history_bytes() const {
  std::lock_guard lock(mutex_);
  return history_.memory_bytes();
}

std::string OperatorView::trend_json(double since) const {
  std::lock_guard lock(mutex_);
  std::string out;
  out.reserve(4096);
  JsonWriter json(out);
  json.begin_object();
  json.number("now", latest_time_);
  json.number("interval_s", interval_s_);
  json.integer("capacity", std::uint64_t{history_.capacity()});
  json.boolean("ack_token_required", ack_token_required_);
  write_service(json, latest_);

  json.begin_array("actuators");
  for (const auto& a : latest_.actuators) {
    json.begin_object();
    write_actuator(json, a);
    // Renamed; kept for one release (views/vocabulary.cpp renamed_fields()).
    json.number("index_p1", a.index_p1);
    json.number("index_p2", a.index_p2);
    json.number("p1", a.p1);
    json.number("p2", a.p2);
    json.number("oil_temperature", a.oil_temperature);
    json.begin_array("channels");
    for (const auto& c : a.channels) {
      json.begin_object();
      json.string("channel", c.channel);
      json.string("status", io::to_string(c.status));
      json.string("fault", detect::to_string(c.fault));  // "none" for none, as it was
      json.integer("spikes_rejected", c.spikes_rejected);
      json.end_object();
    }
    json.end_array();
    // Renamed columns; kept for one release.
    write_trend(json, history_.actuator(a.name), since, trend_columns(),
                {{"index_p1", "index_p1_pa"},
                 {"index_p2", "index_p2_pa"},
                 {"p1", "p1_pa"},
                 {"p2", "p2_pa"},
                 {"oil_temperature", "oil_temperature_c"},
                 {"alarm", "alarm_state_code"}});
    json.end_object();
  }
  json.end_array();

  json.begin_array("groups");
  for (const auto& g : latest_.groups) {
    json.begin_object();
    write_group(json, g);
    // Renamed; kept for one release.
    json.number("latency_mean_us", g.wakeup_latency.mean_us());
    json.number("latency_max_us", g.wakeup_latency.max_us());
    json.number("latency_p99_us", g.wakeup_latency.p99_us());
    write_trend(json, history_.group(g.name), since, loop_trend_columns(),
                {{"latency_mean_us", "wakeup_latency_mean_us"}});
    json.end_object();
  }
  json.end_array();

  json.begin_array("drivers");
  for (const auto& d : latest_.drivers) {
    json.begin_object();
    write_driver(json, d);
    json.end_object();
  }
  json.end_array();
  json.end_object();
  return out;
}

std::optional<http::HttpResponse> OperatorView::handle(const http::HttpRequest& request) const {
  if (request.method != "GET" && request.method != "HEAD") return std::nullopt;
  // Parameters come decoded from the transport (http/http_target.hpp); the first of a repeated
  // one counts, and others are ignored, as a browser's cache-busting parameter may be.
  if (request.path == "/api/trend") {
    const http::QueryParam* since = http::find_param(request.params, "since");
    double value = 0.0;
    if (since != nullptr && !since->value.empty()) {
      char* end = nullptr;
      value = std::strtod(since->value.c_str(), &end);
      if (end == nullptr || *end != '\0' || !std::isfinite(value)) {
        return bad_request(
            fmt::format("since: '{}' is not a unix time in seconds\n", since->value));
      }
    }
    return json_response(trend_json(value));
  }
  if (request.path == "/api/events") {
    const http::QueryParam* after = http::find_param(request.params, "after");
    unsigned long long value = 0;
    if (after != nullptr && !after->value.empty()) {
      char* end = nullptr;
      value = std::strtoull(after->value.c_str(), &end, 10);
      if (end == nullptr || *end != '\0') {
        return bad_request(fmt::format("after: '{}' is not an event number\n", after->value));
      }
    }
    return json_response(events_->json_after(value));
  }
  // Both arms string_view: a std::string arm would make a temporary the view outlives.
  const std::string_view path =
      request.path == "/index.html" ? std::string_view("/") : std::string_view(request.path);
  for (const auto& asset : web_assets()) {
    if (asset.path == path) {
      // The page's policy as a header too: the meta tag cannot forbid framing.
      return http::HttpResponse{200,
                                std::string(asset.content_type),
                                std::string(asset.body),
                                {{"Content-Security-Policy",
                                  "default-src 'none'; script-src 'self'; style-src 'self'; "
                                  "img-src 'self'; connect-src 'self'; frame-ancestors 'none'"},
                                 {"X-Content-Type-Options", "nosniff"}}};
    }
  }
  return std::nullopt;
}

}  // namespace leakmon::views
