#include "io/canlog/candump.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace leakmon::io::canlog {
namespace {

LogRecord parse_ok(std::string_view line) {
  LogRecord r;
  ParseProblem p;
  EXPECT_EQ(parse_candump_line(line, r, p), LineKind::frame)
      << line << ": col " << p.column << ": " << p.message;
  return r;
}

ParseProblem parse_bad(std::string_view line) {
  LogRecord r;
  ParseProblem p;
  EXPECT_EQ(parse_candump_line(line, r, p), LineKind::error) << line;
  return p;
}

TEST(CandumpParser, ClassicStandardFrame) {
  const LogRecord r = parse_ok("(1436509052.249713) vcan0 044#2A366C2A");
  EXPECT_EQ(r.time_ns, 1436509052249713000);
  EXPECT_EQ(r.interface, "vcan0");
  EXPECT_EQ(r.frame.id, 0x44U);
  EXPECT_FALSE(r.frame.extended);
  EXPECT_FALSE(r.frame.fd);
  ASSERT_EQ(r.frame.length, 4);
  EXPECT_EQ(r.frame.data[0], 0x2A);
  EXPECT_EQ(r.frame.data[3], 0x2A);
}

TEST(CandumpParser, ExtendedEmptyAndSeparatedData) {
  LogRecord r = parse_ok("(0.5) can0 1F334455#11.22.33");
  EXPECT_EQ(r.time_ns, 500'000'000);
  EXPECT_TRUE(r.frame.extended);
  EXPECT_EQ(r.frame.id, 0x1F334455U);
  EXPECT_EQ(r.frame.length, 3);
  EXPECT_EQ(r.frame.data[2], 0x33);
  r = parse_ok("(1.000001) can0 7FF#");
  EXPECT_EQ(r.frame.length, 0);
  EXPECT_EQ(r.time_ns, 1'000'001'000);
  r = parse_ok("(1.000000) can0 00000123#abcdef");
  EXPECT_TRUE(r.frame.extended) << "8 digits make a 29-bit id even when the value is small";
  EXPECT_EQ(r.frame.data[0], 0xAB);
}

TEST(CandumpParser, CanFdWithFlags) {
  const LogRecord r =
      parse_ok("(1.0) can0 123##3000102030405060708090A0B0C0D0E0F101112131415161718191A1B1C1D1E1F");
  EXPECT_TRUE(r.frame.fd);
  EXPECT_EQ(r.frame.fd_flags, 3);
  ASSERT_EQ(r.frame.length, 32);
  EXPECT_EQ(r.frame.data[31], 0x1F);
  EXPECT_EQ(parse_ok("(1.0) can0 123##0").frame.length, 0);
}

TEST(CandumpParser, RemoteErrorLen8DlcAndDirection) {
  LogRecord r = parse_ok("(1.0) can0 123#R");
  EXPECT_TRUE(r.frame.remote);
  EXPECT_EQ(r.frame.length, 0);
  r = parse_ok("(1.0) can0 123#R5");
  EXPECT_EQ(r.frame.length, 5);
  r = parse_ok("(1.0) can0 20000040#0000000000000000");
  EXPECT_TRUE(r.frame.error);
  EXPECT_FALSE(r.frame.extended);
  EXPECT_EQ(r.frame.id, 0x40U) << "CAN_ERR_BUSOFF";
  r = parse_ok("(1.0) can0 123#1122334455667788_C");
  EXPECT_EQ(r.frame.length, 8);
  r = parse_ok("(1.0) can0 123#11 R");
  EXPECT_EQ(r.frame.length, 1);
  r = parse_ok("(1.0) can0 123#11 T\r");
  EXPECT_EQ(r.frame.data[0], 0x11);
}

TEST(CandumpParser, SkipsBlankAndCommentLines) {
  LogRecord r;
  ParseProblem p;
  EXPECT_EQ(parse_candump_line("", r, p), LineKind::skip);
  EXPECT_EQ(parse_candump_line("   ", r, p), LineKind::skip);
  EXPECT_EQ(parse_candump_line("# recorded on the rig", r, p), LineKind::skip);
}

TEST(CandumpParser, ErrorsPointAtTheColumn) {
  struct Case {
    const char* line;
    unsigned column;
    const char* words;
  };
  const Case cases[] = {
      {"1.0) can0 123#00", 1, "'('"},
      {"(1,0) can0 123#00", 3, "'.'"},
      {"(1.) can0 123#00", 4, "fraction"},
      {"(1.0 can0 123#00", 5, "')'"},
      {"(1.0)can0 123#00", 6, "space"},
      {"(1.0) can0", 11, "CAN id"},
      {"(1.0) can0 12#00", 12, "3 hex digits"},
      {"(1.0) can0 800#00", 12, "0x7FF"},
      {"(1.0) can0 123456789#00", 20, "more than 8"},
      {"(1.0) can0 123#0G", 17, "hex digit"},
      {"(1.0) can0 123#001", 19, "odd number"},
      {"(1.0) can0 123#001122334455667788", 32, "more than 8 data bytes"},
      {"(1.0) can0 123##", 17, "flags"},
      {"(1.0) can0 123#R9", 17, "0..8"},
      {"(1.0) can0 123#11 X", 19, "unexpected text"},
      {"(1.0) can0 123#11_9", 18, "only follows 8"},
      {"(99999999999.0) can0 123#11", 11, "out of range"},
      {"(1.0123456789) can0 123#11", 13, "9 digits"},
      {"(1.0) can0 20000040##100", 21, "error frame"},
      {"(1.0) can0 5FFFFFFF#00", 12, "flag bits"},
  };
  for (const Case& c : cases) {
    const ParseProblem p = parse_bad(c.line);
    EXPECT_EQ(p.column, c.column) << c.line << ": " << p.message;
    EXPECT_NE(std::string(p.message).find(c.words), std::string::npos)
        << c.line << ": " << p.message;
  }
}

TEST(CandumpParser, FileErrorsNameFileLineAndColumn) {
  const std::string text =
      "(1.000000) can0 101#0102\n"
      "\n"
      "(1.002000) can0 101#01Z2\n";
  try {
    parse_candump_text(text, "bus.log");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "bus.log:3:23: expected a hex digit in the data");
  }
  try {
    parse_candump_text("(2.0) can0 101#01\n(1.0) can0 101#02\n", "bus.log");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bus.log:2:2: timestamp goes backwards"),
              std::string::npos)
        << e.what();
  }
}

TEST(CandumpParser, InterfaceFilterAndLineNumbers) {
  const CandumpLog log = parse_candump_text(
      "(1.0) can0 101#01\n(1.1) can1 101#02\n# note\n(1.2) can0 101#03\n", "x.log", "can0");
  ASSERT_EQ(log.frames.size(), 2U);
  EXPECT_EQ(log.frames[1].line, 4U);
  EXPECT_EQ(log.frames[1].frame.data[0], 3);
  EXPECT_EQ(log.interfaces, std::vector<std::string>{"can0"});
}

}  // namespace
}  // namespace leakmon::io::canlog
