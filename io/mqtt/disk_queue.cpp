#include "io/mqtt/disk_queue.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>

namespace leakmon::io::mqtt {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kMagic = 0x3151'4D4C;  // "LMQ1" little-endian
constexpr std::size_t kHeaderBytes = 24;
constexpr std::size_t kCursorBytes = 12;
// A record larger than this is not one the output ever writes: corruption.
constexpr std::uint32_t kMaxFieldBytes = 64u << 20;

std::uint32_t crc32_update(std::uint32_t crc, std::string_view bytes) {
  static constexpr auto kTable = [] {
    std::array<std::uint32_t, 256> table{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB8'8320u ^ (c >> 1) : c >> 1;
      table[i] = c;
    }
    return table;
  }();
  crc = ~crc;
  for (unsigned char b : bytes) crc = kTable[(crc ^ b) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xFF);
}
void put_u64(std::string& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out += static_cast<char>((v >> (8 * i)) & 0xFF);
}
std::uint64_t get_le(const char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(p[i]);
  return v;
}

std::uint32_t record_crc(std::uint64_t sequence, std::string_view topic, std::string_view payload) {
  std::string seq;
  put_u64(seq, sequence);
  return crc32_update(crc32_update(crc32_update(0, seq), topic), payload);
}

std::string errno_text(int error) { return std::system_category().message(error); }

void write_all(int fd, std::string_view bytes, const std::string& path) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(fmt::format("{}: write failed: {}", path, errno_text(errno)));
    }
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
}

void sync_fd(int fd, const std::string& path) {
  if (::fdatasync(fd) != 0) {
    throw std::runtime_error(fmt::format("{}: fdatasync failed: {}", path, errno_text(errno)));
  }
}

// A new or renamed directory entry is durable only once the directory itself is synced.
void sync_directory(const std::string& directory) {
  const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

std::string read_file(const std::string& path) {
  std::string data;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENOENT) return data;
    throw std::runtime_error(fmt::format("{}: cannot open: {}", path, errno_text(errno)));
  }
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error = errno;
      ::close(fd);
      throw std::runtime_error(fmt::format("{}: read failed: {}", path, errno_text(error)));
    }
    if (n == 0) break;
    data.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return data;
}

std::string segment_name(std::uint64_t first) { return fmt::format("{:020d}.seg", first); }

}  // namespace

std::uint64_t DiskQueue::record_bytes(std::string_view topic, std::string_view payload) {
  return kHeaderBytes + topic.size() + payload.size();
}

DiskQueue::DiskQueue(std::string directory, DiskQueueLimits limits)
    : directory_(std::move(directory)), limits_(limits) {
  std::error_code error;
  fs::create_directories(directory_, error);
  if (error) {
    throw std::runtime_error(
        fmt::format("{}: cannot create the queue directory: {}", directory_, error.message()));
  }
  const std::string lock_path = directory_ + "/lock";
  lock_fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (lock_fd_ < 0) {
    throw std::runtime_error(fmt::format("{}: cannot open: {}", lock_path, errno_text(errno)));
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    ::close(lock_fd_);
    lock_fd_ = -1;
    if (e == EWOULDBLOCK) {
      throw DiskQueueBusy(
          fmt::format("{}: the queue is in use by another output or process", directory_));
    }
    throw std::runtime_error(fmt::format("{}: cannot lock: {}", lock_path, errno_text(e)));
  }
  try {
    recover();
  } catch (...) {
    if (active_fd_ >= 0) ::close(active_fd_);
    ::close(lock_fd_);
    throw;
  }
}

DiskQueue::~DiskQueue() {
  if (active_fd_ >= 0) ::close(active_fd_);
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
}

void DiskQueue::recover() {
  const std::string cursor_path = directory_ + "/acked";
  const std::string cursor = read_file(cursor_path);
  if (cursor.size() == kCursorBytes) {
    const std::uint64_t acked = get_le(cursor.data(), 8);
    std::string seq;
    put_u64(seq, acked);
    if (crc32_update(0, seq) == static_cast<std::uint32_t>(get_le(cursor.data() + 8, 4))) {
      acked_ = acked;
    }
  }
  // A missing or damaged cursor means starting from 0: messages may go out twice, never lost.

  for (const auto& entry : fs::directory_iterator(directory_)) {
    const std::string name = entry.path().filename().string();
    if (name.size() != 24 || name.substr(20) != ".seg") continue;
    if (!std::all_of(name.begin(), name.begin() + 20, [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    Segment segment;
    segment.first = std::stoull(name.substr(0, 20));
    if (segment.first == 0) continue;
    segment.path = entry.path().string();
    segments_.push_back(segment);
  }
  std::sort(segments_.begin(), segments_.end(),
            [](const Segment& a, const Segment& b) { return a.first < b.first; });
  next_sequence_ = acked_ + 1;
  for (auto& segment : segments_) scan_segment(segment, acked_);
  // Segments that hold nothing pending go now; appends start a fresh segment.
  std::vector<Segment> kept;
  for (auto& segment : segments_) {
    const bool pending = segment.size > 0 && segment.last > acked_;
    if (pending) {
      kept.push_back(segment);
    } else {
      ::unlink(segment.path.c_str());
    }
  }
  segments_ = std::move(kept);
  if (!segments_.empty()) {
    const Segment& last = segments_.back();
    active_fd_ = ::open(last.path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
    if (active_fd_ < 0) {
      throw std::runtime_error(fmt::format("{}: cannot open: {}", last.path, errno_text(errno)));
    }
  }
}

void DiskQueue::scan_segment(Segment& segment, std::uint64_t acked) {
  const std::string data = read_file(segment.path);
  std::size_t offset = 0;
  segment.last = segment.first - 1;  // sequences within a segment are contiguous
  while (offset + kHeaderBytes <= data.size()) {
    const char* header = data.data() + offset;
    const auto magic = static_cast<std::uint32_t>(get_le(header, 4));
    const auto topic_bytes = static_cast<std::uint32_t>(get_le(header + 4, 4));
    const auto payload_bytes = static_cast<std::uint32_t>(get_le(header + 8, 4));
    const std::uint64_t sequence = get_le(header + 12, 8);
    const auto crc = static_cast<std::uint32_t>(get_le(header + 20, 4));
    if (magic != kMagic || topic_bytes > kMaxFieldBytes || payload_bytes > kMaxFieldBytes) break;
    const std::size_t end = offset + kHeaderBytes + topic_bytes + payload_bytes;
    if (end > data.size()) break;
    const std::string_view topic(data.data() + offset + kHeaderBytes, topic_bytes);
    const std::string_view payload(data.data() + offset + kHeaderBytes + topic_bytes,
                                   payload_bytes);
    if (record_crc(sequence, topic, payload) != crc || sequence != segment.last + 1) break;
    if (sequence > acked) {
      pending_.push_back(QueuedMessage{sequence, std::string(topic), std::string(payload)});
      pending_bytes_ += record_bytes(topic, payload);
    }
    segment.last = sequence;
    next_sequence_ = std::max(next_sequence_, sequence + 1);
    offset = end;
  }
  segment.size = offset;
  if (offset < data.size()) {
    // A torn write at the end (crash mid-append) or damage: everything from here is cut off,
    // so that later appends follow a valid record.
    truncated_bytes_ += data.size() - offset;
    if (::truncate(segment.path.c_str(), static_cast<off_t>(offset)) != 0) {
      throw std::runtime_error(
          fmt::format("{}: cannot cut off a torn record: {}", segment.path, errno_text(errno)));
    }
  }
}

void DiskQueue::write_cursor(std::uint64_t acked) {
  std::string bytes;
  put_u64(bytes, acked);
  put_u32(bytes, crc32_update(0, bytes));
  const std::string path = directory_ + "/acked";
  const std::string temporary = path + ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) {
    throw std::runtime_error(fmt::format("{}: cannot open: {}", temporary, errno_text(errno)));
  }
  try {
    write_all(fd, bytes, temporary);
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  // Not synced: a cursor lost in a crash only moves back (or, damaged, to 0), so messages go out
  // again, never missing; syncing it would double the disk flushes per event.
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    throw std::runtime_error(fmt::format("{}: cannot rename: {}", path, errno_text(errno)));
  }
}

void DiskQueue::open_active(std::uint64_t first) {
  if (active_fd_ >= 0) ::close(active_fd_);
  active_fd_ = -1;
  Segment segment;
  segment.first = first;
  segment.last = first - 1;
  segment.path = directory_ + "/" + segment_name(first);
  active_fd_ =
      ::open(segment.path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_TRUNC | O_CLOEXEC, 0600);
  if (active_fd_ < 0) {
    throw std::runtime_error(fmt::format("{}: cannot create: {}", segment.path, errno_text(errno)));
  }
  sync_directory(directory_);
  segments_.push_back(segment);
}

bool DiskQueue::append(std::string_view topic, std::string_view payload) {
  const std::uint64_t size = record_bytes(topic, payload);
  if (pending_.size() + 1 > limits_.max_events || pending_bytes_ + size > limits_.max_bytes) {
    return false;
  }
  if (segments_.empty() || active_fd_ < 0 || segments_.back().size >= limits_.segment_bytes) {
    open_active(next_sequence_);
  }
  Segment& active = segments_.back();
  const std::uint64_t sequence = next_sequence_;
  std::string record;
  record.reserve(size);
  put_u32(record, kMagic);
  put_u32(record, static_cast<std::uint32_t>(topic.size()));
  put_u32(record, static_cast<std::uint32_t>(payload.size()));
  put_u64(record, sequence);
  put_u32(record, record_crc(sequence, topic, payload));
  record += topic;
  record += payload;
  try {
    write_all(active_fd_, record, active.path);
    sync_fd(active_fd_, active.path);
  } catch (...) {
    // A partial record would hide every later one from recovery: cut it off.
    if (::ftruncate(active_fd_, static_cast<off_t>(active.size)) != 0) {
      ::close(active_fd_);
      active_fd_ = -1;  // the next append starts a new segment
    }
    throw;
  }
  active.size += record.size();
  active.last = sequence;
  next_sequence_ = sequence + 1;
  pending_.push_back(QueuedMessage{sequence, std::string(topic), std::string(payload)});
  pending_bytes_ += size;
  return true;
}

void DiskQueue::pop_front() {
  if (pending_.empty()) return;
  const QueuedMessage& front = pending_.front();
  write_cursor(front.sequence);
  acked_ = front.sequence;
  pending_bytes_ -= record_bytes(front.topic, front.payload);
  pending_.pop_front();
  drop_acknowledged_segments();
}

void DiskQueue::drop_acknowledged_segments() {
  // Every segment but the active one, once all it holds is acknowledged; the active one too
  // when it is full and everything is acknowledged (the next append starts another).
  while (!segments_.empty() && segments_.front().last <= acked_) {
    const bool active = segments_.size() == 1;
    if (active && segments_.front().size < limits_.segment_bytes) break;
    if (active) {
      ::close(active_fd_);
      active_fd_ = -1;
    }
    ::unlink(segments_.front().path.c_str());
    segments_.erase(segments_.begin());
  }
}

}  // namespace leakmon::io::mqtt
