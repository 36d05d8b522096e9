#include "views/operator_view.hpp"

#include <fmt/format.h>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>

#include "capture/units.hpp"
#include "config/yaml_reader.hpp"
#include "daemon/daemon.hpp"
#include "pipeline/event_log.hpp"
#include "views/web_assets.hpp"
#include "io/event_json.hpp"

namespace leakmon::views {
namespace {

double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

using io::append_json_string;

// JSON has no NaN: a value the daemon does not have yet is null. Seven digits are more than
// any sensor resolves; times (unix seconds) keep milliseconds.
void append_number(std::string& out, double value) {
  if (std::isfinite(value)) {
    fmt::format_to(std::back_inserter(out), "{:.7g}", value);
  } else {
    out += "null";
  }
}

void append_time(std::string& out, double unix_time) {
  if (std::isfinite(unix_time)) {
    fmt::format_to(std::back_inserter(out), "{:.3f}", unix_time);
  } else {
    out += "null";
  }
}

// "key": value pairs, comma-separated within one object.
class JsonFields {
 public:
  explicit JsonFields(std::string& out) : out_(out) { out_ += '{'; }
  ~JsonFields() { out_ += '}'; }
  JsonFields(const JsonFields&) = delete;
  JsonFields& operator=(const JsonFields&) = delete;

  std::string& key(std::string_view name) {
    if (!first_) out_ += ',';
    first_ = false;
    append_json_string(out_, name);
    out_ += ':';
    return out_;
  }
  void string(std::string_view name, std::string_view value) {
    append_json_string(key(name), value);
  }
  void number(std::string_view name, double value) { append_number(key(name), value); }
  void time(std::string_view name, double value) { append_time(key(name), value); }
  void integer(std::string_view name, std::uint64_t value) {
    fmt::format_to(std::back_inserter(key(name)), "{}", value);
  }
  void boolean(std::string_view name, bool value) { key(name) += value ? "true" : "false"; }
  // A column of the ring's points after `from`, e.g. the score of every point.
  template <typename Ring, typename Value>
  void column(std::string_view name, const Ring& ring, std::size_t from, Value value) {
    std::string& out = key(name);
    out += '[';
    for (std::size_t i = from; i < ring.size(); ++i) {
      if (i > from) out += ',';
      append_number(out, value(ring[i]));
    }
    out += ']';
  }
  template <typename Ring>
  void time_column(const Ring& ring, std::size_t from) {
    std::string& out = key("time");
    out += '[';
    for (std::size_t i = from; i < ring.size(); ++i) {
      if (i > from) out += ',';
      append_time(out, ring[i].unix_time);
    }
    out += ']';
  }

 private:
  std::string& out_;
  bool first_ = true;
};

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

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

http::HttpResponse json_response(std::string body) {
  return {200, "application/json; charset=utf-8", std::move(body)};
}

}  // namespace

std::string query_value(std::string_view query, std::string_view key) {
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view{} : query.substr(amp + 1);
    const auto eq = pair.find('=');
    if (pair.substr(0, eq) != key) continue;
    if (eq == std::string_view::npos) return {};
    std::string value;
    const std::string_view raw = pair.substr(eq + 1);
    for (std::size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] == '+') {
        value += ' ';
      } else if (raw[i] == '%') {
        if (i + 2 >= raw.size() || hex_digit(raw[i + 1]) < 0 || hex_digit(raw[i + 2]) < 0) {
          return {};
        }
        value += static_cast<char>(hex_digit(raw[i + 1]) * 16 + hex_digit(raw[i + 2]));
        i += 2;
      } else {
        value += raw[i];
      }
    }
    return value;
  }
  return {};
}

bool same_token(std::string_view given, std::string_view expected) {
  unsigned difference = given.size() == expected.size() ? 0u : 1u;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const char g = i < given.size() ? given[i] : '\0';
    difference |= static_cast<unsigned>(static_cast<unsigned char>(g) ^
                                        static_cast<unsigned char>(expected[i]));
  }
  return difference == 0;
}

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
      ack_token_(config.metrics.ack_token) {}

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
  sample(unix_now());  // the page has a point at once
  sampler_ = std::thread([this] { run_sampler(); });
}

void OperatorView::run_sampler() {
  const auto interval = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(interval_s_));
  auto next = std::chrono::steady_clock::now() + interval;
  std::unique_lock lock(stop_mutex_);
  while (!stop_signal_.wait_until(lock, next, [this] { return stop_; })) {
    lock.unlock();
    sample(unix_now());
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

void OperatorView::set_ack_token(const std::string& token) {
  std::lock_guard lock(mutex_);
  ack_token_ = token;
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
  JsonFields root(out);
  root.time("now", latest_time_);
  root.number("interval_s", interval_s_);
  root.integer("capacity", history_.capacity());
  root.boolean("ack_token_required", !ack_token_.empty());
  root.integer("samples_processed", latest_.samples_processed);
  root.integer("events", latest_.events);
  root.number("decision_latency_p99_us",
              static_cast<double>(latest_.decision_latency_p99_ns) / 1e3);

  root.key("actuators") += '[';
  bool first_actuator = true;
  for (const auto& a : latest_.actuators) {
    if (!first_actuator) out += ',';
    first_actuator = false;
    JsonFields item(out);
    item.string("name", a.name);
    item.string("alarm", a.alarm);
    item.string("detector", a.detector);
    item.string("state", to_string(a.state));
    item.boolean("learning", a.learning);
    item.boolean("suspended", a.suspended);
    item.boolean("detection_blind", a.detection_blind);
    item.number("t", a.t);
    item.number("index_p1", a.index_p1);
    item.number("index_p2", a.index_p2);
    item.number("score", a.score);
    item.number("raise_threshold", a.raise_threshold);
    item.number("clear_threshold", a.clear_threshold);
    item.number("leak_lpm_per_mpa", units::lpm_per_mpa(a.leak_coefficient));
    item.number("leak_lpm_per_mpa_ci95", units::lpm_per_mpa(a.leak_coefficient_ci));
    item.number("p1", a.p1);
    item.number("p2", a.p2);
    item.number("oil_temperature", a.oil_temperature);
    item.integer("decisions", a.decisions);
    item.key("channels") += '[';
    for (std::size_t i = 0; i < a.channels.size(); ++i) {
      if (i > 0) out += ',';
      const auto& c = a.channels[i];
      JsonFields channel(out);
      channel.string("channel", c.channel);
      channel.string("status", io::to_string(c.status));
      channel.string("fault", detect::to_string(c.fault));
      channel.integer("spikes_rejected", c.spikes_rejected);
    }
    out += ']';
    const auto* series = history_.actuator(a.name);
    item.key("trend");
    if (series == nullptr) {
      out += "null";
      continue;
    }
    const auto& ring = series->points;
    const std::size_t from = first_after(ring, since);
    JsonFields trend(out);
    trend.time_column(ring, from);
    trend.column("index_p1", ring, from, [](const TrendPoint& p) { return p.index_p1; });
    trend.column("index_p2", ring, from, [](const TrendPoint& p) { return p.index_p2; });
    trend.column("score", ring, from, [](const TrendPoint& p) { return p.score; });
    trend.column("raise_threshold", ring, from,
                 [](const TrendPoint& p) { return p.raise_threshold; });
    trend.column("leak_lpm_per_mpa", ring, from,
                 [](const TrendPoint& p) { return p.leak_lpm_per_mpa; });
    trend.column("leak_lpm_per_mpa_ci95", ring, from,
                 [](const TrendPoint& p) { return p.leak_lpm_per_mpa_ci95; });
    trend.column("p1", ring, from, [](const TrendPoint& p) { return p.p1; });
    trend.column("p2", ring, from, [](const TrendPoint& p) { return p.p2; });
    trend.column("oil_temperature", ring, from,
                 [](const TrendPoint& p) { return p.oil_temperature; });
    trend.column("alarm", ring, from,
                 [](const TrendPoint& p) { return static_cast<double>(p.alarm); });
  }
  out += ']';

  root.key("groups") += '[';
  bool first_group = true;
  for (const auto& g : latest_.groups) {
    if (!first_group) out += ',';
    first_group = false;
    JsonFields item(out);
    item.string("name", g.group);
    item.boolean("realtime", g.realtime);
    item.integer("cycles", g.cycles);
    item.integer("overruns", g.overruns);
    item.integer("missed_cycles", g.missed_cycles);
    item.integer("ring_drops", g.ring_drops);
    item.integer("ring_high_water", g.ring_high_water);
    item.integer("ring_capacity", g.ring_capacity);
    item.number("latency_mean_us", g.latency_count == 0
                                       ? NAN
                                       : static_cast<double>(g.latency_sum_ns) /
                                             static_cast<double>(g.latency_count) / 1e3);
    item.number("latency_max_us", static_cast<double>(g.latency_max_ns) / 1e3);
    item.number("latency_p99_us", static_cast<double>(g.latency_p99_ns) / 1e3);
    const auto* series = history_.group(g.group);
    item.key("trend");
    if (series == nullptr) {
      out += "null";
      continue;
    }
    const auto& ring = series->points;
    const std::size_t from = first_after(ring, since);
    JsonFields trend(out);
    trend.time_column(ring, from);
    trend.column("latency_mean_us", ring, from,
                 [](const LoopPoint& p) { return p.latency_mean_us; });
    trend.column("overruns", ring, from,
                 [](const LoopPoint& p) { return static_cast<double>(p.overruns); });
  }
  out += ']';
  return out;
}

std::optional<http::HttpResponse> OperatorView::handle(const http::HttpRequest& request) const {
  if (request.path == "/ack") {
    std::string token;
    {
      std::lock_guard lock(mutex_);
      token = ack_token_;
    }
    // The token as a query parameter (the page, `leakmon ack`) or as a bearer credential.
    constexpr std::string_view kBearer = "Bearer ";
    const std::string_view authorization = request.authorization;
    const bool bearer_ok = authorization.substr(0, kBearer.size()) == kBearer &&
                           same_token(authorization.substr(kBearer.size()), token);
    if (token.empty() || bearer_ok || same_token(query_value(request.query, "token"), token)) {
      return std::nullopt;  // the daemon acknowledges
    }
    return http::HttpResponse{401, "text/plain; charset=utf-8",
                              "acknowledging needs the token of metrics.ack_token: POST "
                              "/ack?actuator=NAME&token=TOKEN\n"};
  }
  if (request.method != "GET" && request.method != "HEAD") return std::nullopt;
  if (request.path == "/api/trend") {
    const std::string since = query_value(request.query, "since");
    char* end = nullptr;
    double value = since.empty() ? 0.0 : std::strtod(since.c_str(), &end);
    if (!since.empty() && (end == nullptr || *end != '\0' || !std::isfinite(value))) {
      return http::HttpResponse{400, "text/plain; charset=utf-8",
                                fmt::format("since: '{}' is not a unix time in seconds\n", since)};
    }
    return json_response(trend_json(value));
  }
  if (request.path == "/api/events") {
    const std::string after = query_value(request.query, "after");
    char* end = nullptr;
    const unsigned long long value = after.empty() ? 0 : std::strtoull(after.c_str(), &end, 10);
    if (!after.empty() && (end == nullptr || *end != '\0')) {
      return http::HttpResponse{400, "text/plain; charset=utf-8",
                                fmt::format("after: '{}' is not an event number\n", after)};
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

// The daemon's side of the sampling: what /metrics reads, into `out` without allocating once
// `out` has the daemon's shape (the groups are fixed; a reload may add actuators).
}  // namespace leakmon::views

// The service's side, until it fills a snapshot the views format.
namespace leakmon::daemon {
using namespace leakmon::views;
void Daemon::fill_view_snapshot(ViewSnapshot& out) const {
  worker_->status_into(out.actuators);
  out.groups.resize(groups_.size());
  for (std::size_t i = 0; i < groups_.size(); ++i) {
    const Group& g = *groups_[i];
    read_loop_health(out.groups[i], g.config.name, g.loop->counters(), g.ring->capacity(),
                     g.realtime.fifo);
  }
  out.samples_processed = worker_->samples_processed();
  out.events = worker_->events_published();
  out.decision_latency_p99_ns = worker_->decision_latency().quantile_ns(0.99);
}
}  // namespace leakmon::daemon

namespace leakmon::views {}  // namespace leakmon::views
