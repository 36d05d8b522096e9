// The MQTT output's durable queue: order, acknowledgement, the bound, recovery after a restart
// and after a torn last write, segment clean-up, and one user at a time.
#include "io/mqtt/disk_queue.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>

#include "tests/support/paths.hpp"

namespace leakmon::io::mqtt {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> segments(const std::string& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".seg") out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> drain(DiskQueue& queue) {
  std::vector<std::string> out;
  while (!queue.empty()) {
    out.push_back(queue.front().payload);
    queue.pop_front();
  }
  return out;
}

std::string fmt_payload(int i) { return (i < 10 ? "payload-0" : "payload-") + std::to_string(i); }

TEST(DiskQueue, KeepsOrderAndRemovesOnlyWhatWasAcknowledged) {
  const std::string dir = test::scratch_dir("mqtt_disk_queue_order");
  DiskQueue queue(dir, {});
  EXPECT_TRUE(queue.empty());
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(queue.append("t/e", "event " + std::to_string(i)));
  EXPECT_EQ(queue.events(), 5u);
  EXPECT_EQ(queue.bytes(), 5 * DiskQueue::record_bytes("t/e", "event 0"));
  EXPECT_EQ(queue.front().payload, "event 0");
  EXPECT_EQ(queue.front().topic, "t/e");
  queue.pop_front();
  EXPECT_EQ(queue.front().payload, "event 1");
  EXPECT_EQ(queue.events(), 4u);
  EXPECT_GT(queue.front().sequence, 1u);
}

TEST(DiskQueue, SurvivesARestartWithOnlyTheUnacknowledgedMessages) {
  const std::string dir = test::scratch_dir("mqtt_disk_queue_restart");
  {
    DiskQueue queue(dir, {});
    for (int i = 0; i < 6; ++i) ASSERT_TRUE(queue.append("t/e", "event " + std::to_string(i)));
    queue.pop_front();
    queue.pop_front();
  }
  {
    DiskQueue queue(dir, {});
    EXPECT_EQ(queue.recovered_truncated_bytes(), 0u);
    ASSERT_EQ(queue.events(), 4u);
    ASSERT_TRUE(queue.append("t/e", "event 6"));  // numbering continues after the old ones
    const auto first = queue.front().sequence;
    EXPECT_EQ(drain(queue),
              (std::vector<std::string>{"event 2", "event 3", "event 4", "event 5", "event 6"}));
    EXPECT_EQ(first, 3u);
  }
  DiskQueue queue(dir, {});
  EXPECT_TRUE(queue.empty());
  EXPECT_TRUE(queue.append("t/e", "event 7"));
  EXPECT_EQ(queue.front().sequence, 8u);
}

TEST(DiskQueue, RefusesMessagesBeyondItsBoundAndTakesThemAgainOnceDrained) {
  const std::string dir = test::scratch_dir("mqtt_disk_queue_bound");
  DiskQueueLimits limits;
  limits.max_events = 3;
  DiskQueue queue(dir, limits);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(queue.append("t", std::to_string(i)));
  EXPECT_FALSE(queue.append("t", "3"));
  EXPECT_EQ(queue.events(), 3u);
  queue.pop_front();
  EXPECT_TRUE(queue.append("t", "4"));
  EXPECT_EQ(drain(queue), (std::vector<std::string>{"1", "2", "4"}));

  const std::string dir_bytes = test::scratch_dir("mqtt_disk_queue_bound_bytes");
  DiskQueueLimits byte_limits;
  byte_limits.max_bytes = 2 * DiskQueue::record_bytes("t", std::string(100, 'x'));
  DiskQueue by_bytes(dir_bytes, byte_limits);
  EXPECT_TRUE(by_bytes.append("t", std::string(100, 'x')));
  EXPECT_TRUE(by_bytes.append("t", std::string(100, 'y')));
  EXPECT_FALSE(by_bytes.append("t", "z"));
  EXPECT_EQ(by_bytes.bytes(), byte_limits.max_bytes);
}

TEST(DiskQueue, CutsOffATornLastRecordAndKeepsEverythingBefore) {
  const std::string dir = test::scratch_dir("mqtt_disk_queue_torn");
  {
    DiskQueue queue(dir, {});
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(queue.append("t/e", "event " + std::to_string(i)));
  }
  const auto files = segments(dir);
  ASSERT_EQ(files.size(), 1u);
  const std::string path = dir + "/" + files[0];
  const auto intact = fs::file_size(path);
  // A crash in the middle of the fourth append: its header and part of its payload.
  {
    std::ofstream out(path, std::ios::binary | std::ios::app);
    const char partial[] = {'L', 'M', 'Q', '1', 3, 0, 0, 0, 50, 0, 0, 0, 4, 0};
    out.write(partial, sizeof partial);
  }
  {
    DiskQueue queue(dir, {});
    EXPECT_EQ(queue.recovered_truncated_bytes(), 14u);
    EXPECT_EQ(fs::file_size(path), intact);
    ASSERT_TRUE(queue.append("t/e", "event 3"));
  }
  DiskQueue queue(dir, {});
  EXPECT_EQ(queue.recovered_truncated_bytes(), 0u);
  EXPECT_EQ(drain(queue), (std::vector<std::string>{"event 0", "event 1", "event 2", "event 3"}));
}

TEST(DiskQueue, ADamagedRecordEndsWhatIsTrusted) {
  const std::string dir = test::scratch_dir("mqtt_disk_queue_crc");
  {
    DiskQueue queue(dir, {});
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(queue.append("t/e", "event " + std::to_string(i)));
  }
  const std::string path = dir + "/" + segments(dir)[0];
  {
    // Flip one payload byte of the second record.
    std::fstream file(path, std::ios::binary | std::ios::in | std::ios::out);
    const auto record = DiskQueue::record_bytes("t/e", "event 0");
    file.seekp(static_cast<std::streamoff>(record + record - 1));
    file.put('X');
  }
  DiskQueue queue(dir, {});
  EXPECT_EQ(drain(queue), (std::vector<std::string>{"event 0"}));
  EXPECT_GT(queue.recovered_truncated_bytes(), 0u);
}

TEST(DiskQueue, DeletesSegmentsOnceEverythingInThemIsAcknowledged) {
  const std::string dir = test::scratch_dir("mqtt_disk_queue_segments");
  DiskQueueLimits limits;
  limits.segment_bytes = 4 * DiskQueue::record_bytes("t", "payload-00");
  DiskQueue queue(dir, limits);
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(queue.append("t", fmt_payload(i)));
  }
  EXPECT_EQ(segments(dir).size(), 3u);  // 4 + 4 + 2 records
  for (int i = 0; i < 4; ++i) queue.pop_front();
  EXPECT_EQ(segments(dir).size(), 2u);
  for (int i = 0; i < 4; ++i) queue.pop_front();
  EXPECT_EQ(segments(dir).size(), 1u);
  EXPECT_EQ(queue.events(), 2u);
}

TEST(DiskQueue, OneUserAtATime) {
  const std::string dir = test::scratch_dir("mqtt_disk_queue_lock");
  auto first = std::make_unique<DiskQueue>(dir, DiskQueueLimits{});
  EXPECT_THROW(DiskQueue(dir, {}), DiskQueueBusy);
  first.reset();
  EXPECT_NO_THROW(DiskQueue(dir, {}));
}

TEST(DiskQueue, AnUnusableDirectoryIsAClearError) {
  const std::string dir = test::scratch_dir("mqtt_disk_queue_file");
  std::ofstream(dir + "/not-a-directory") << "x";
  try {
    DiskQueue queue(dir + "/not-a-directory/q", {});
    FAIL() << "opened a queue under a file";
  } catch (const DiskQueueBusy&) {
    FAIL() << "reported busy";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not-a-directory/q"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace leakmon::io::mqtt
