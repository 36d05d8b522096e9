// The MQTT output's durable queue of events not yet acknowledged by the broker: append-only
// segment files in one directory, every append fsync'd before it counts, a message removed only
// after its PUBACK (an acknowledgement cursor, replaced by rename and not synced: after a
// power cut it may lag, and messages go out twice rather than never). Survives a restart or a
// crash; a torn last record (power cut mid-write) is cut off when the queue is opened.
//
// Layout of `directory`: `lock` (flock: one queue user at a time), `acked` (the sequence number
// of the newest acknowledged message, with a CRC), and segments `<first sequence>.seg`
// (20 digits) holding records
//   u32 magic "LMQ1" | u32 topic bytes | u32 payload bytes | u64 sequence | u32 CRC-32 | topic |
//   payload
// (little-endian; the CRC covers sequence, topic and payload). A segment is deleted once every
// record in it is acknowledged and a newer segment has been started.
#pragma once

#include <cstdint>
#include <deque>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace leakmon::io::mqtt {

struct QueuedMessage {
  std::uint64_t sequence = 0;
  std::string topic;
  std::string payload;
};

struct DiskQueueLimits {
  std::uint64_t max_events = 10000;
  std::uint64_t max_bytes = 16u << 20;  // records not yet acknowledged
  // A new segment starts when the active one reaches this size; the disk holds at most about
  // max_bytes + segment_bytes.
  std::uint64_t segment_bytes = 1u << 20;
};

// Another process or output holds the queue directory's lock.
class DiskQueueBusy : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class DiskQueue {
 public:
  // Opens or creates `directory`, locks it and recovers what it holds. Throws DiskQueueBusy when
  // locked elsewhere, std::runtime_error (naming the file) when it cannot be read or created.
  DiskQueue(std::string directory, DiskQueueLimits limits);
  ~DiskQueue();
  DiskQueue(const DiskQueue&) = delete;
  DiskQueue& operator=(const DiskQueue&) = delete;

  // Appends durably (written and fdatasync'd when it returns true). False, writing nothing, when
  // the message would exceed max_events or max_bytes: the queue keeps what it holds and the
  // caller counts the refusal. Throws std::runtime_error on a write error (disk full...).
  bool append(std::string_view topic, std::string_view payload);

  bool empty() const { return pending_.empty(); }
  const QueuedMessage& front() const { return pending_.front(); }
  // The oldest message was acknowledged: the cursor moves past it and segments that
  // hold only acknowledged messages go.
  void pop_front();

  std::uint64_t events() const { return pending_.size(); }
  std::uint64_t bytes() const { return pending_bytes_; }
  const std::string& directory() const { return directory_; }
  // What opening found: bytes cut off a torn or corrupt segment end (0 normally).
  std::uint64_t recovered_truncated_bytes() const { return truncated_bytes_; }

  static std::uint64_t record_bytes(std::string_view topic, std::string_view payload);

 private:
  struct Segment {
    std::uint64_t first = 0;  // sequence numbers held: [first, last]
    std::uint64_t last = 0;
    std::uint64_t size = 0;  // bytes
    std::string path;
  };
  void recover();
  void scan_segment(Segment& segment, std::uint64_t acked);
  void write_cursor(std::uint64_t acked);
  void open_active(std::uint64_t first);
  void drop_acknowledged_segments();

  std::string directory_;
  DiskQueueLimits limits_;
  int lock_fd_ = -1;
  int active_fd_ = -1;  // the newest segment, appended to
  std::vector<Segment> segments_;
  std::deque<QueuedMessage> pending_;
  std::uint64_t pending_bytes_ = 0;
  std::uint64_t acked_ = 0;          // newest acknowledged sequence
  std::uint64_t next_sequence_ = 1;  // of the next append
  std::uint64_t truncated_bytes_ = 0;
};

}  // namespace leakmon::io::mqtt
