// The capture CSV reader and writer (capture/): exact round trip, gaps, errors naming
// file:line:column, non-increasing time, missing header, unknown columns kept.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include "capture/capture.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::capture {
namespace {

std::string write_file(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

// The message of the CaptureError that reading the whole file raises ("" when none).
std::string read_error(const std::string& path) {
  try {
    (void)read_capture(path);
  } catch (const CaptureError& e) {
    return e.what();
  }
  return "";
}

TEST(Capture, RoundTripIsExact) {
  const std::string dir = test::scratch_dir("capture_round_trip");
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Capture original;
  original.metadata = {{"sample_rate_hz", "500"}, {"source", "test seed 3"}};
  original.columns = {"t", "p1", "x", "weird_sensor"};
  original.values.assign(4, {});
  for (int i = 0; i < 1000; ++i) {
    original.values[0].push_back(i * 0.002);
    original.values[1].push_back(8.65e6 + 1e5 * uniform(rng));
    // Positions from 1e-23 m to 1 mm: every exponent, within x's physical range (+-10 m).
    original.values[2].push_back(1e-3 * uniform(rng) *
                                 std::pow(10.0, -20 * std::abs(uniform(rng))));
    original.values[3].push_back(i % 97 == 5 ? kGap : uniform(rng));
  }
  const std::string path = dir + "/capture.csv";
  write_capture(path, original);
  const Capture back = read_capture(path);
  EXPECT_EQ(back.columns, original.columns);
  EXPECT_EQ(back.metadata, original.metadata);
  ASSERT_EQ(back.rows(), 1000u);
  for (std::size_t c = 0; c < 4; ++c) {
    for (std::size_t r = 0; r < 1000; ++r) {
      const double a = original.values[c][r];
      const double b = back.values[c][r];
      if (std::isnan(a)) {
        EXPECT_TRUE(std::isnan(b)) << c << "," << r;
      } else {
        EXPECT_EQ(a, b) << c << "," << r;  // bit-exact, not approximately
      }
    }
  }
  EXPECT_EQ(back.sample_rate_hz(), 500.0);
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "# leakmon capture v1");
}

TEST(Capture, EmptyFieldsAndNanAreGapsNotZeros) {
  const std::string dir = test::scratch_dir("capture_gaps");
  const std::string path = write_file(dir, "gaps.csv",
                                      "# leakmon capture v1\n"
                                      "t,p1,p2\n"
                                      "0.000,1.5,2\n"
                                      "0.002,,3\n"
                                      "0.004,NaN,nan\n"
                                      "0.006,0,-0\n");
  const Capture c = read_capture(path);
  ASSERT_EQ(c.rows(), 4u);
  EXPECT_EQ(c.column("p1")[0], 1.5);
  EXPECT_TRUE(std::isnan(c.column("p1")[1]));
  EXPECT_EQ(c.column("p2")[1], 3.0);
  EXPECT_TRUE(std::isnan(c.column("p1")[2]));
  EXPECT_TRUE(std::isnan(c.column("p2")[2]));
  EXPECT_EQ(c.column("p1")[3], 0.0);
  EXPECT_FALSE(std::isnan(c.column("p2")[3]));
}

TEST(Capture, UnknownColumnsAreKeptInAnyOrder) {
  const std::string dir = test::scratch_dir("capture_unknown");
  const std::string path = write_file(dir, "c.csv", "p2,t,coolant_temp\n4,0,21.5\n5,0.002,21.6\n");
  const Capture c = read_capture(path);
  EXPECT_EQ(c.columns, (std::vector<std::string>{"p2", "t", "coolant_temp"}));
  EXPECT_EQ(c.column("coolant_temp")[1], 21.6);
  EXPECT_EQ(c.column("t")[1], 0.002);
  EXPECT_FALSE(c.has("p1"));
  EXPECT_THROW((void)c.column("p1"), CaptureError);
  CaptureReader reader(path);
  EXPECT_EQ(reader.t_index(), 1u);
  EXPECT_EQ(reader.column_index("coolant_temp"), 2u);
}

TEST(Capture, MalformedLinesNameFileLineAndColumn) {
  const std::string dir = test::scratch_dir("capture_malformed");
  struct Bad {
    std::string body;
    std::string expected;  // after "<path>:"
  };
  const Bad cases[] = {
      {"# c\nt,p1\n0,1\n0.002,abc\n", "4:2: column 'p1': 'abc' is not a number"},
      {"t,p1\n0,1\n0.002,1,7\n", "3:3: too many fields"},
      {"t,p1,p2\n0,1,2\n0.002,1\n", "3:2: too few fields"},
      {"t,p1\n0,1\n0.002,1\ninf,1\n", "4:1: column 't': 'inf' is not a finite time"},
      {"t,p1\n0,1\n,2\n", "3:1: column 't' is empty"},
      {"t,p1\n0,1.5e\n", "2:2: column 'p1': '1.5e' is not a number"},
  };
  int i = 0;
  for (const Bad& bad : cases) {
    const std::string path = write_file(dir, "bad" + std::to_string(i++) + ".csv", bad.body);
    const std::string message = read_error(path);
    EXPECT_TRUE(message.starts_with(path + ":" + bad.expected)) << message;
  }
}

TEST(Capture, NonFiniteAndAbsurdValuesBecomeCountedGaps) {
  const std::string dir = test::scratch_dir("capture_absurd");
  // p1 1e308 and inf, p2 -5 MPa (below a pressure transducer's range), x 1e999 (beyond double),
  // u -inf; the plausible values next to them stay.
  const std::string path = write_file(dir, "absurd.csv",
                                      "t,p1,p2,x,u\n"
                                      "0,8e6,7e6,0.01,1\n"
                                      "0.002,1e308,7e6,0.01,1\n"
                                      "0.004,inf,-5e6,1e999,-inf\n"
                                      "0.006,8e6,7e6,0.02,2\n");
  CaptureReader reader(path);
  std::vector<double> row(5);
  std::size_t rows = 0;
  std::size_t gaps = 0;
  while (reader.next(row)) {
    ++rows;
    for (double v : row) gaps += std::isnan(v) ? 1 : 0;
    for (double v : row) EXPECT_FALSE(std::isinf(v));
  }
  EXPECT_EQ(rows, 4u);
  EXPECT_EQ(gaps, 5u);
  EXPECT_EQ(reader.rejected_values(), 5u);
  const Capture whole = read_capture(path);
  EXPECT_EQ(whole.column("p1")[0], 8e6);
  EXPECT_TRUE(std::isnan(whole.column("p1")[1]));
  EXPECT_EQ(whole.column("x")[3], 0.02);
}

TEST(Capture, ByteOrderMarkIsSkipped) {
  const std::string dir = test::scratch_dir("capture_bom");
  const std::string path = write_file(dir, "bom.csv", "\xef\xbb\xbft,p1\n0,1\n0.002,2\n");
  const Capture capture = read_capture(path);
  EXPECT_EQ(capture.columns, (std::vector<std::string>{"t", "p1"}));
  EXPECT_EQ(capture.rows(), 2u);
}

TEST(Capture, HeaderOnlyIsNoSamplesWithOrWithoutMetadata) {
  const std::string dir = test::scratch_dir("capture_header_only");
  for (const std::string body : {"t,p1\n", "# sample_rate_hz: 500\nt,p1\n# end\n"}) {
    const std::string path = write_file(dir, "empty.csv", body);
    EXPECT_EQ(read_error(path), path + ": no samples (a header but not a single row)");
  }
}

TEST(Capture, ErrorsQuoteOnlyAnExcerpt) {
  const std::string dir = test::scratch_dir("capture_excerpt");
  const std::string path =
      write_file(dir, "long.csv", "t,p1\n0," + std::string(1 << 20, 'x') + "\n");
  const std::string message = read_error(path);
  EXPECT_LT(message.size(), 200u) << message.substr(0, 300);
  EXPECT_NE(message.find("xxx...' is not a number"), std::string::npos) << message.substr(0, 300);
  const std::string escape = write_file(dir, "escape.csv", "t,p1\n0,\x1b[2J\n");
  EXPECT_EQ(read_error(escape).find('\x1b'), std::string::npos);
}

TEST(Capture, TimeMustStrictlyIncrease) {
  const std::string dir = test::scratch_dir("capture_time");
  const std::string repeat = write_file(dir, "repeat.csv", "t,p1\n0,1\n0.002,1\n0.002,1\n");
  EXPECT_TRUE(read_error(repeat).starts_with(repeat + ":4:1: column 't': 0.002 does not increase"))
      << read_error(repeat);
  const std::string back = write_file(dir, "back.csv", "p1,t\n1,0.004\n1,0.002\n");
  EXPECT_TRUE(read_error(back).starts_with(back + ":3:2: column 't'")) << read_error(back);
}

TEST(Capture, HeaderProblemsAreReported) {
  const std::string dir = test::scratch_dir("capture_header");
  const std::string only_comments = write_file(dir, "none.csv", "# leakmon capture v1\n# a: b\n");
  EXPECT_TRUE(read_error(only_comments).starts_with(only_comments + ":3: no header line"))
      << read_error(only_comments);
  const std::string no_t = write_file(dir, "no_t.csv", "time,p1\n0,1\n");
  EXPECT_TRUE(read_error(no_t).starts_with(no_t + ":1:1: header has no 't' column"))
      << read_error(no_t);
  const std::string twice = write_file(dir, "twice.csv", "t,p1,p1\n0,1,2\n");
  EXPECT_TRUE(read_error(twice).starts_with(twice + ":1:3: duplicate column 'p1'"))
      << read_error(twice);
  const std::string empty_name = write_file(dir, "empty_name.csv", "t,,p1\n");
  EXPECT_TRUE(read_error(empty_name).starts_with(empty_name + ":1:2: empty column name"))
      << read_error(empty_name);
  EXPECT_TRUE(read_error(dir + "/missing.csv").find("cannot open") != std::string::npos);
}

TEST(Capture, MetadataAndCommentsBetweenRows) {
  const std::string dir = test::scratch_dir("capture_metadata");
  const std::string path = write_file(dir, "m.csv",
                                      "# leakmon capture v1\n"
                                      "# sample_rate_hz: 250\n"
                                      "# source: sim preset paper-fig13 seed 7\n"
                                      "t,p1\n"
                                      "0,1\n"
                                      "# a comment among the rows\n"
                                      "\n"
                                      "0.004,2\n");
  CaptureReader reader(path);
  EXPECT_EQ(reader.metadata_value("source"), "sim preset paper-fig13 seed 7");
  std::vector<double> row(2);
  ASSERT_TRUE(reader.next(row));
  EXPECT_EQ(reader.line_number(), 5u);
  ASSERT_TRUE(reader.next(row));
  EXPECT_EQ(reader.line_number(), 8u);
  EXPECT_EQ(row[1], 2.0);
  EXPECT_FALSE(reader.next(row));
  EXPECT_EQ(read_capture(path).sample_rate_hz(), 250.0);
}

TEST(Capture, SampleRateFromTimesWhenNoMetadata) {
  const std::string dir = test::scratch_dir("capture_rate");
  const std::string path = write_file(dir, "r.csv", "t,p1\n0,1\n0.002,1\n0.004,1\n0.010,1\n");
  EXPECT_NEAR(read_capture(path).sample_rate_hz(), 500.0, 1e-9);
  const std::string bad = write_file(dir, "bad.csv", "# sample_rate_hz: fast\nt,p1\n0,1\n");
  EXPECT_THROW((void)read_capture(bad).sample_rate_hz(), CaptureError);
}

TEST(Capture, WriterNeedsATimeColumn) {
  const std::string dir = test::scratch_dir("capture_writer");
  EXPECT_THROW(CaptureWriter(dir + "/w.csv", {"p1"}, {}), CaptureError);
}

}  // namespace
}  // namespace leakmon::capture
