// The model check refuses data it cannot diagnose, with a reason naming file, line and column.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>

#include "capture/capture.hpp"
#include "model/measured_record.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::model {
namespace {

// A healthy-looking capture of `seconds` at 500 Hz with the given header: readings at rest,
// each moving by an LSB as a real transducer's do (a value held exactly is a fault).
std::string write_capture(const std::string& name, const std::string& header, double seconds,
                          const std::string& row_text = "0.001,{x},{p},{p}") {
  const std::string path = test::scratch_dir(name) + "/capture.csv";
  std::ofstream out(path);
  out << "# leakmon capture v1\n# sample_rate_hz: 500\n" << header << "\n";
  const int rows = static_cast<int>(seconds * 500.0);
  for (int i = 0; i < rows; ++i) {
    out << i * 0.002 << ","
        << fmt::format(fmt::runtime(row_text), fmt::arg("x", 1e-5 * (i % 3)),
                       fmt::arg("p", 8.6e6 + 5054.0 * (i % 2)))
        << "\n";
  }
  return path;
}

std::string error_of(const std::string& path) {
  try {
    read_measured_record(path);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(ModelRecord, AcceptsAWellFormedCapture) {
  const auto path = write_capture("model_record_ok", "t,u,x,p1,p2", 25.0);
  const MeasuredRecord r = read_measured_record(path);
  EXPECT_EQ(r.size(), 12500u);
  EXPECT_NEAR(r.dt, 0.002, 1e-12);
  EXPECT_NEAR(r.duration(), 25.0, 1e-9);
}

TEST(ModelRecord, RefusesMissingColumnsNamingThem) {
  const auto path = write_capture("model_record_columns", "t,u,x,p1", 25.0, "0.001,0.0,8.6e6");
  const std::string error = error_of(path);
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("'p2'"), std::string::npos) << error;
}

TEST(ModelRecord, RefusesTooShortData) {
  const auto path = write_capture("model_record_short", "t,u,x,p1,p2", 5.0);
  const std::string error = error_of(path);
  EXPECT_NE(error.find("too short"), std::string::npos) << error;
  EXPECT_NE(error.find(path), std::string::npos) << error;
}

TEST(ModelRecord, RefusesGapRiddenDataNamingTheFirstGap) {
  const std::string path = test::scratch_dir("model_record_gaps") + "/capture.csv";
  std::ofstream out(path);
  out << "# leakmon capture v1\nt,u,x,p1,p2\n";
  for (int i = 0; i < 12500; ++i) {
    out << i * 0.002 << ",0.001,0.0," << (i % 10 == 3 ? "" : "8.6e6") << ",8.6e6\n";
  }
  out.close();
  const std::string error = error_of(path);
  EXPECT_NE(error.find("gaps"), std::string::npos) << error;
  EXPECT_NE(error.find("line 6, column p1"), std::string::npos) << error;  // row 4 = line 6
}

TEST(ModelRecord, RefusesIrregularSamplingNamingTheLine) {
  const std::string path = test::scratch_dir("model_record_irregular") + "/capture.csv";
  std::ofstream out(path);
  out << "t,u,x,p1,p2\n";
  for (int i = 0; i < 12500; ++i) out << (i < 100 ? i * 0.002 : i * 0.002 + 0.01) << ",0,0,1,1\n";
  out.close();
  const std::string error = error_of(path);
  EXPECT_NE(error.find(path + ":102: column t"), std::string::npos) << error;
}

TEST(ModelRecord, MalformedValuesAreCaptureErrorsWithLineAndColumn) {
  const std::string path = test::scratch_dir("model_record_malformed") + "/capture.csv";
  std::ofstream out(path);
  out << "t,u,x,p1,p2\n0,0,0,1,1\n0.002,0,abc,1,1\n";
  out.close();
  EXPECT_THROW(read_measured_record(path), capture::CaptureError);
  const std::string error = error_of(path);
  EXPECT_NE(error.find(":3"), std::string::npos) << error;
}

// p1 swinging about 11 MPa by `peak` at `hz` on a 20.7 MPa, 12-bit transducer, quantised and
// clipped at its range ends; with `knocks`, once a second the piston knocks into a stop and p1
// shoots past the range for 16 ms. p2 swings half as far, never clipped.
std::string write_clipped_capture(const std::string& name, double peak, bool knocks = false,
                                  double hz = 0.5) {
  const std::string path = test::scratch_dir(name) + "/capture.csv";
  std::ofstream out(path);
  out << "# leakmon capture v1\nt,u,x,p1,p2\n";
  const double lsb = 20.7e6 / 4096.0;
  for (int i = 0; i < 12500; ++i) {
    const double t = i * 0.002;
    const double swing = std::sin(2.0 * M_PI * hz * t);
    const int since_knock = i % 500;
    const double knock =
        knocks && since_knock < 10 ? 12e6 * std::sin(M_PI * since_knock / 10.0) : 0.0;
    const double p1 =
        std::clamp(std::nearbyint((11e6 + peak * swing + knock) / lsb), 0.0, 4095.0) * lsb;
    const double p2 = std::nearbyint((11e6 - 0.5 * peak * swing) / lsb) * lsb;
    out << t << ",0.001," << fmt::format("{},{:.9g},{:.9g}", 1e-5 * (i % 3), p1, p2) << "\n";
  }
  return path;
}

// The readings at the top code say only "at least this much": left out of the fit and the
// scores (invalid), reported as pinned; the other channel and every sample below stay.
TEST(ModelRecord, PressureClippedAtItsRangeEndIsLeftOut) {
  const auto path = write_clipped_capture("model_record_clipped", 6e6, true);
  const MeasuredRecord r = read_measured_record(path);
  ASSERT_EQ(r.censored.size(), 1u);
  EXPECT_EQ(r.censored[0].reason, MeasuredRecord::Censored::Reason::range_end);
  EXPECT_EQ(r.censored[0].channel, "p1");
  const double top = 4095.0 * 20.7e6 / 4096.0;
  EXPECT_NEAR(r.censored[0].value, top, 1.0);
  std::size_t at_top = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    const bool pinned = std::abs(r.p1[i] - top) < 1.0;
    at_top += pinned;
    EXPECT_EQ(r.valid[i], !pinned) << "row " << i;
  }
  EXPECT_EQ(r.censored[0].samples, at_top);
  EXPECT_GT(at_top, 100u);
}

// A pressure that reaches its largest value on a smooth crest (here a sine that peaks below
// the top code) lands there a few times like on its neighbours: nothing is pinned.
TEST(ModelRecord, APressureCrestingBelowItsRangeEndIsNotPinned) {
  const auto path = write_clipped_capture("model_record_crest", 9.5e6);
  const MeasuredRecord r = read_measured_record(path);
  EXPECT_TRUE(r.censored.empty()) << r.censored.front().channel;
  for (std::size_t i = 0; i < r.size(); ++i) ASSERT_TRUE(r.valid[i]) << "row " << i;
}

// Clipped on a third of the samples (a 5 Hz swing of 20 MPa, each clip shorter than a held
// run), more than the model check leaves out: refused, naming the column, the value and the
// first clipped line.
TEST(ModelRecord, RefusesAPressureMostlyAtItsRangeEndNamingIt) {
  const auto path = write_clipped_capture("model_record_saturated", 20e6, false, 5.0);
  const std::string error = error_of(path);
  EXPECT_NE(error.find("column p1 sits at"), std::string::npos) << error;
  EXPECT_NE(error.find("range end"), std::string::npos) << error;
  EXPECT_NE(error.find(path + ":"), std::string::npos) << error;
}

// A transducer frozen for a second (its DAQ holds the last value): the run is left out and
// reported; the readings around it, moving by an LSB at rest, all stay.
TEST(ModelRecord, AFrozenRunIsLeftOutAndTheRestStays) {
  const std::string path = test::scratch_dir("model_record_frozen") + "/capture.csv";
  std::ofstream out(path);
  out << "t,u,x,p1,p2\n";
  for (int i = 0; i < 12500; ++i) {
    const bool frozen = i >= 5000 && i < 5500;
    out << fmt::format("{},0.001,{},{},{}\n", i * 0.002, 1e-5 * (i % 3), 9e6 + 5054.0 * (i % 2),
                       frozen ? 8.6e6 : 8.6e6 + 5054.0 * (i % 2));
  }
  out.close();
  const MeasuredRecord r = read_measured_record(path);
  ASSERT_EQ(r.censored.size(), 1u);
  const auto& p2 = r.censored[0];
  EXPECT_EQ(p2.channel, "p2");
  EXPECT_EQ(p2.reason, MeasuredRecord::Censored::Reason::held);
  EXPECT_EQ(p2.runs, 1u);
  EXPECT_EQ(p2.first, "5002");  // row 5000 under the header
  EXPECT_EQ(p2.samples, 501u);  // row 5500 reads 8.6e6 as well
  for (std::size_t i = 0; i < r.size(); ++i) {
    ASSERT_EQ(r.valid[i], i < 5000 || i > 5500) << "row " << i;
  }
}

// Five isolated 3 MPa spikes on p1 (electrical interference) are replaced by their
// neighbours' median and counted; the rows stay valid. p2 swinging 4 MPa at 5 Hz (a fast
// swing, none of whose samples stands apart from its neighbours) keeps every reading.
TEST(ModelRecord, IsolatedSpikesAreReplacedByTheirNeighboursMedian) {
  const std::string path = test::scratch_dir("model_record_spikes") + "/capture.csv";
  std::ofstream out(path);
  out << "t,u,x,p1,p2\n";
  const double lsb = 20.7e6 / 4096.0;
  for (int i = 0; i < 12500; ++i) {
    const double p1 = 9e6 + lsb * (i % 2) + (i % 2400 == 1000 ? 3e6 : 0.0);
    const double p2 =
        std::nearbyint((10e6 + 4e6 * std::sin(2.0 * M_PI * 5.0 * i * 0.002)) / lsb) * lsb;
    out << fmt::format("{},0.001,{},{:.9g},{:.9g}\n", i * 0.002, 1e-5 * (i % 3), p1, p2);
  }
  out.close();
  const MeasuredRecord r = read_measured_record(path);
  ASSERT_EQ(r.censored.size(), 1u);
  EXPECT_EQ(r.censored[0].channel, "p1");
  EXPECT_EQ(r.censored[0].reason, MeasuredRecord::Censored::Reason::spikes);
  EXPECT_EQ(r.censored[0].samples, 5u);  // rows 1000, 3400, 5800, 8200, 10600
  EXPECT_EQ(r.censored[0].first, "1002");
  for (std::size_t i = 0; i < r.size(); ++i) {
    ASSERT_TRUE(r.valid[i]) << "row " << i;
    ASSERT_LT(r.p1[i], 9.1e6) << "row " << i;
  }
}

}  // namespace
}  // namespace leakmon::model
