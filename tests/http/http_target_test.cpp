// The request-target parser and the router, on the inputs issue 15 found answered wrongly
// (`?%%%%`, HEAD and POST on /metrics) and on the encodings a client may legitimately use. The
// service's parameter checks (`/ack?foo=bar`, `?actuator`, `?actuator=`) are
// tests/daemon/routes_test.cpp's.
#include <gtest/gtest.h>

#include "http/http_router.hpp"
#include "http/http_target.hpp"

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

}  // namespace
}  // namespace leakmon::http
