// The one JSON number and string writer (io/event_json.hpp) and the views' object writer on it:
// numbers in their shortest round-trip form everywhere; a value that is not finite is null in a
// document and left out of a message, never NaN; strings always valid UTF-8 JSON. Before, three
// writers had three rules (status: shortest and null; page: 7 digits and null, times to the
// millisecond; events: shortest and left out).
#include "views/json_writer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "io/event_json.hpp"

namespace leakmon::views {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string number(double value) {
  std::string out;
  io::append_json_number(out, value);
  return out;
}

TEST(JsonNumber, ShortestRoundTripAndNullForWhatIsNotFinite) {
  EXPECT_EQ(number(0.1), "0.1");
  EXPECT_EQ(number(1.5), "1.5");
  EXPECT_EQ(number(25849.3), "25849.3");
  EXPECT_EQ(number(-2.0), "-2");
  EXPECT_EQ(number(1795441542.678), "1795441542.678");
  EXPECT_EQ(number(2.18e-12), "2.18e-12");
  // Every double reads back as itself: nothing is rounded away (the page's 7 digits were).
  for (const double value : {1.0 / 3.0, 21345.678901234, 6.5e6 + 0.1, 1e-300, 123456789.0}) {
    EXPECT_EQ(std::stod(number(value)), value) << number(value);
  }
  EXPECT_EQ(number(kNaN), "null");
  EXPECT_EQ(number(kInf), "null");
  EXPECT_EQ(number(-kInf), "null");
}

TEST(JsonString, AlwaysValidJson) {
  using io::json_string;
  EXPECT_EQ(json_string("a\"b\\c\n\x01"), "\"a\\\"b\\\\c\\n\\u0001\"");
  EXPECT_EQ(json_string("\xc3\xa9"), "\"\xc3\xa9\"");
  EXPECT_EQ(json_string("x\xff\xc3"), "\"x\\ufffd\\ufffd\"");           // invalid, truncated
  EXPECT_EQ(json_string("\xed\xa0\x80"), "\"\\ufffd\\ufffd\\ufffd\"");  // a surrogate
  EXPECT_EQ(json_string("\x1b[31m"), "\"\\u001b[31m\"");                // ESC reaches no terminal
}

TEST(JsonWriter, DocumentWritesNullForWhatIsNotKnown) {
  std::string out;
  JsonWriter json(out);
  json.begin_object();
  json.number("a", 0.25);
  json.number("nan", kNaN);
  json.number("inf", kInf);
  json.string_or_null("none", "");
  json.string("text", "x\"y");
  json.integer("count", std::uint64_t{7});
  json.integer("negative", std::int64_t{-3});
  json.boolean("flag", true);
  json.begin_array("list");
  json.number({}, 1.0);
  json.number({}, kNaN);
  json.begin_object();
  json.null("empty");
  json.end_object();
  json.end_array();
  json.begin_object("nested");
  json.end_object();
  json.end_object();
  EXPECT_EQ(out, R"({"a":0.25,"nan":null,"inf":null,"none":null,"text":"x\"y","count":7,)"
                 R"("negative":-3,"flag":true,"list":[1,null,{"empty":null}],"nested":{}})");
}

TEST(JsonWriter, MessageLeavesOutWhatIsNotKnownAndIsSpacedLikeAnEvent) {
  std::string out;
  JsonWriter json(out, JsonWriter::Style::message);
  json.begin_object();
  json.number("t", 11.038);
  json.number("score", kNaN);
  json.string("actuator", "cyl");
  json.string_or_null("fault", "");
  json.boolean("learning", false);
  json.end_object();
  EXPECT_EQ(out, R"({"t": 11.038, "actuator": "cyl", "learning": false})");
  // The event's own object builder writes numbers with the same writer.
  io::JsonObject event;
  event.number("t", 11.038);
  event.number("score", kNaN);
  event.string("actuator", "cyl");
  event.boolean("learning", false);
  EXPECT_EQ(event.finish(), out);
}

TEST(JsonWriter, UnbalancedNestingIsAProgrammingError) {
  std::string out;
  JsonWriter json(out);
  EXPECT_THROW(json.end_object(), std::logic_error);
  for (std::size_t i = 0; i < JsonWriter::kMaxDepth; ++i) json.begin_array();
  EXPECT_THROW(json.begin_array(), std::logic_error);
}

// The event log's lines are written as before, byte for byte (replays are compared with the
// previous build's by docs/developing.md's procedure; this pins one line here).
TEST(JsonNumber, EventLinesAreUnchanged) {
  io::Event event;
  event.kind = io::EventKind::alarm_raised;
  event.t = 61.998000000000005;
  event.actuator = "cylinder";
  event.alarm = "internal_leakage";
  event.channel = "p1";
  event.index = 24940.0;
  event.score = 1.97;
  event.leak_coefficient = 1.595e-12;
  event.leak_lpm_per_mpa = 0.0957;
  event.latched = false;
  EXPECT_EQ(io::to_json_line(event),
            R"({"t": 61.998000000000005, "event": "alarm_raised", "actuator": "cylinder", )"
            R"("alarm": "internal_leakage", "channel": "p1", "index": 24.94, "score": 1.97, )"
            R"("leak_coefficient": 1.595e-12, "leak_lpm_per_mpa": 0.0957, "latched": false})");
}

}  // namespace
}  // namespace leakmon::views
