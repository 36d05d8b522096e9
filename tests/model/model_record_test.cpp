// The model check refuses data it cannot diagnose, with a reason naming file, line and column.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "capture/capture.hpp"
#include "model/measured_record.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::model {
namespace {

// A healthy-looking capture of `seconds` at 500 Hz with the given header.
std::string write_capture(const std::string& name, const std::string& header, double seconds,
                          const std::string& row_text = "0.001,0.0,8.6e6,8.6e6") {
  const std::string path = test::scratch_dir(name) + "/capture.csv";
  std::ofstream out(path);
  out << "# leakmon capture v1\n# sample_rate_hz: 500\n" << header << "\n";
  const int rows = static_cast<int>(seconds * 500.0);
  for (int i = 0; i < rows; ++i) out << i * 0.002 << "," << row_text << "\n";
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

}  // namespace
}  // namespace leakmon::model
