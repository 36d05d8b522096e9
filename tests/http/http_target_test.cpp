// The request-target parser and the router checks, on the inputs issue 15 found answered wrongly
// (`/ack?foo=bar`, `?actuator`, `?actuator=`, `?%%%%`, HEAD and POST on /metrics) and on the
// encodings a client may legitimately use.
#include <gtest/gtest.h>

#include <cmath>

#include "http/http_router.hpp"
#include "http/http_target.hpp"
#include "views/status_json.hpp"
#include "io/event_json.hpp"

namespace leakmon::http {
namespace {

RequestTarget parsed(std::string_view text) {
  const RequestTargetResult result = parse_request_target(text);
  EXPECT_TRUE(result.target.has_value()) << text << ": " << result.error;
  return result.target.value_or(RequestTarget{});
}

std::string error_of(std::string_view text) {
  const RequestTargetResult result = parse_request_target(text);
  EXPECT_FALSE(result.target.has_value()) << text << " was accepted";
  return result.error;
}

TEST(HttpTarget, SplitsAtAmpersandAndFirstEquals) {
  const RequestTarget t = parsed("/ack?actuator=cyl&x=a=b&&flag&");
  EXPECT_EQ(t.path, "/ack");
  EXPECT_EQ(t.query, "actuator=cyl&x=a=b&&flag&");
  ASSERT_EQ(t.params.size(), 3u);
  EXPECT_EQ(t.params[0].name, "actuator");
  EXPECT_EQ(t.params[0].value, "cyl");
  EXPECT_EQ(t.params[1].name, "x");
  EXPECT_EQ(t.params[1].value, "a=b");
  EXPECT_EQ(t.params[2].name, "flag");
  EXPECT_FALSE(t.params[2].has_value);
  EXPECT_TRUE(t.params[0].has_value);
}

TEST(HttpTarget, PercentDecodesNamesValuesAndPath) {
  const RequestTarget t = parsed("/st%61tus?actuator=left%20arm%2Bboom&a%26b=c%3Dd&sp=a+b");
  EXPECT_EQ(t.path, "/status");
  ASSERT_EQ(t.params.size(), 3u);
  EXPECT_EQ(t.params[0].value, "left arm+boom");
  EXPECT_EQ(t.params[1].name, "a&b");
  EXPECT_EQ(t.params[1].value, "c=d");
  EXPECT_EQ(t.params[2].value, "a b");                           // '+' is a space in a query
  EXPECT_EQ(parsed("/a+b").path, "/a+b");                        // but not in the path
  EXPECT_EQ(parsed("/x?n=%c3%a9").params[0].value, "\xc3\xa9");  // UTF-8 passes through
  EXPECT_TRUE(parsed("/metrics").params.empty());
  EXPECT_EQ(parsed("/metrics?").query, "");
}

TEST(HttpTarget, MalformedEscapesAndControlCharactersAreErrors) {
  for (const char* bad :
       {"/ack?%%%%", "/ack?actuator=%", "/ack?actuator=%4", "/ack?a=%zz", "/ack?a=%4g", "/m%",
        "/ack?a=%00", "/ack?a=%0a", "/ack?a=%7f", "/ack?%0d%0aSet-Cookie:x=1"}) {
    EXPECT_NE(error_of(bad).find("malformed"), std::string::npos) << bad;
  }
  EXPECT_NE(error_of("").find("'/'"), std::string::npos);
  EXPECT_NE(error_of("metrics").find("'/'"), std::string::npos);
  EXPECT_NE(error_of("http://host/metrics").find("'/'"), std::string::npos);
  EXPECT_NE(error_of("/metrics#top").find("fragment"), std::string::npos);
  EXPECT_EQ(percent_decode("100%25", false).value_or("?"), "100%");
  EXPECT_FALSE(percent_decode("100%", false).has_value());
}

HttpRequest request(std::string method, std::string target) {
  const RequestTarget t = parsed(target);
  return HttpRequest{std::move(method), t.path, t.query, t.params, ""};
}

std::string header(const HttpResponse& response, const std::string& name) {
  for (const auto& [key, value] : response.headers) {
    if (key == name) return value;
  }
  return "(none)";
}

TEST(HttpRouter, RoutesByPathAndMethodWith405AndAllow) {
  int served = 0;
  const HttpRoute routes[] = {
      {"/metrics", "GET",
       [&](const HttpRequest&) {
         ++served;
         return HttpResponse{200, "t", "m"};
       }},
      {"/ack", "POST",
       [&](const HttpRequest&) {
         ++served;
         return HttpResponse{200, "t", "a"};
       }},
  };
  EXPECT_EQ(route(routes, request("GET", "/metrics")).body, "m");
  EXPECT_EQ(route(routes, request("HEAD", "/metrics")).body, "m");  // the transport drops it
  EXPECT_EQ(served, 2);
  const HttpResponse post = route(routes, request("POST", "/metrics"));
  EXPECT_EQ(post.status, 405);
  EXPECT_EQ(header(post, "Allow"), "GET, HEAD");
  const HttpResponse get_ack = route(routes, request("GET", "/ack"));
  EXPECT_EQ(get_ack.status, 405);
  EXPECT_EQ(header(get_ack, "Allow"), "POST");
  const HttpResponse missing = route(routes, request("GET", "/metric"));
  EXPECT_EQ(missing.status, 404);
  EXPECT_NE(missing.body.find("GET /metrics"), std::string::npos);
  EXPECT_EQ(served, 2);  // nothing was served for the errors
}

TEST(HttpRouter, AckIsStrictAboutItsParameters) {
  EXPECT_FALSE(ack_selection(request("POST", "/ack")).error);
  EXPECT_EQ(ack_selection(request("POST", "/ack")).actuator, "");  // all
  const AckSelection one = ack_selection(request("POST", "/ack?actuator=left%20boom"));
  EXPECT_FALSE(one.error);
  EXPECT_EQ(one.actuator, "left boom");
  for (const char* bad :
       {"/ack?foo=bar", "/ack?actuator", "/ack?actuator=", "/ack?actuatr=cyl",
        "/ack?actuator=cyl&actuator=cyl", "/ack?actuator=cyl&all=1", "/ack?Actuator=cyl"}) {
    const AckSelection selection = ack_selection(request("POST", bad));
    ASSERT_TRUE(selection.error) << bad;
    EXPECT_EQ(selection.error->status, 400) << bad;
  }
}

TEST(HttpRouter, StatusFormatFromParameterOrAccept) {
  EXPECT_FALSE(status_format(request("GET", "/status")).text);
  EXPECT_TRUE(status_format(request("GET", "/status?format=text")).text);
  EXPECT_FALSE(status_format(request("GET", "/status?format=json")).text);
  HttpRequest plain = request("GET", "/status");
  plain.accept = "text/plain";
  EXPECT_TRUE(status_format(plain).text);
  plain.accept = "application/json, text/plain;q=0.5";
  EXPECT_FALSE(status_format(plain).text);
  for (const char* bad :
       {"/status?format=xml", "/status?verbose=1", "/status?format=text&format=text"}) {
    const StatusFormat format = status_format(request("GET", bad));
    ASSERT_TRUE(format.error) << bad;
    EXPECT_EQ(format.error->status, 400) << bad;
  }
}

TEST(StatusJson, StringsAreAlwaysValidJsonAndNumbersNeverNan) {
  using io::json_string;
  EXPECT_EQ(json_string("a\"b\\c\n\x01"), "\"a\\\"b\\\\c\\n\\u0001\"");
  EXPECT_EQ(json_string("\xc3\xa9"), "\"\xc3\xa9\"");
  EXPECT_EQ(json_string("x\xff\xc3"), "\"x\\ufffd\\ufffd\"");           // invalid, truncated
  EXPECT_EQ(json_string("\xed\xa0\x80"), "\"\\ufffd\\ufffd\\ufffd\"");  // a surrogate
  EXPECT_EQ(views::json_number(NAN), "null");
  EXPECT_EQ(views::json_number(INFINITY), "null");
  EXPECT_EQ(views::json_number(1.5), "1.5");
}

// The human form from a document as the daemon writes it, with values not known yet.
TEST(StatusJson, HumanFormSaysWhatIsNotKnownInsteadOfNan) {
  const std::string json =
      R"({"version":"0.1.0","uptime_s":12.4,"config":"demo.yaml","reload":{"ok":true},)"
      R"("groups":[{"name":"main","cycles":6000,"overruns":0,"missed_cycles":0,"ring_drops":0,)"
      R"("ring_high_water":3,"ring_capacity":8192,"realtime":false,)"
      R"("wakeup_latency_us":{"mean":null,"max":null},"ended":false}],)"
      R"("drivers":[{"name":"rig","status":"ok","detail":"ok","last_error":null,"errors":0}],)"
      R"("actuators":[{"name":"cyl","detector":"flow_balance","state":"learning",)"
      R"("learning_seconds_left":22.3,"t":12.0,"index_pa":{"p1":25000,"p2":null},"score":null,)"
      R"("threshold":{"raise":1,"clear":0.5},"baseline_pa":null,)"
      R"("leak_lpm_per_mpa":{"estimate":null,"ci95":null},"oil_temperature_c":null,)"
      R"("alarms":[{"name":"internal_leakage","state":"normal"}],"suspended":false,)"
      R"("sensors":[{"channel":"p2","status":"ok","fault":null,"spikes_rejected":0}]}]})";
  const std::string text = views::status_text_from_json(json);
  EXPECT_EQ(text.find("nan"), std::string::npos) << text;
  EXPECT_NE(text.find("learning, 23 s left"), std::string::npos) << text;
  EXPECT_NE(text.find("p2 n/a"), std::string::npos) << text;
  EXPECT_NE(text.find("leak estimate n/a"), std::string::npos) << text;
  EXPECT_NE(text.find("channel p2: ok"), std::string::npos) << text;
  EXPECT_THROW(views::status_text_from_json("not json {"), std::runtime_error);
  EXPECT_THROW(views::status_text_from_json("{\"x\":1}"), std::runtime_error);
}

}  // namespace
}  // namespace leakmon::http
