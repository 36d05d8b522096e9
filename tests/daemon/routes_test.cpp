// The service's own routes' checks on requests as the transport hands them over: the query
// decoded once by the fuzzed parser (http/http_target.cpp), never a second decoder. POST /ack's
// strictness (issue 15's `/ack?foo=bar`, `?actuator`, `?actuator=`), its token, and GET /status's
// format.
#include "daemon/routes.hpp"

#include <gtest/gtest.h>

#include "tests/support/http_request.hpp"

namespace leakmon::daemon {
namespace {

using test::request;

TEST(DaemonRoutes, AckIsStrictAboutItsParameters) {
  EXPECT_FALSE(ack_selection(request("POST", "/ack")).error);
  EXPECT_EQ(ack_selection(request("POST", "/ack")).actuator, "");  // all
  const AckSelection one = ack_selection(request("POST", "/ack?actuator=left%20boom"));
  EXPECT_FALSE(one.error);
  EXPECT_EQ(one.actuator, "left boom");
  EXPECT_EQ(ack_selection(request("POST", "/ack?actuator=left+boom&token=x")).actuator,
            "left boom");
  for (const char* bad : {"/ack?foo=bar", "/ack?actuator", "/ack?actuator=", "/ack?actuatr=cyl",
                          "/ack?actuator=cyl&actuator=cyl", "/ack?actuator=cyl&all=1",
                          "/ack?Actuator=cyl", "/ack?token=a&token=a"}) {
    const AckSelection selection = ack_selection(request("POST", bad));
    ASSERT_TRUE(selection.error) << bad;
    EXPECT_EQ(selection.error->status, 400) << bad;
  }
}

TEST(DaemonRoutes, AckTokenComesThroughTheOneDecoder) {
  const std::string token = "s3cret-token-0123456789";
  EXPECT_FALSE(ack_refusal(request("POST", "/ack?actuator=cyl"), "")) << "no token configured";
  const auto refused = ack_refusal(request("POST", "/ack?actuator=cyl"), token);
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 401);
  EXPECT_NE(refused->body.find("metrics.ack_token"), std::string::npos);
  EXPECT_TRUE(ack_refusal(request("POST", "/ack?actuator=cyl&token=s3cret-token-012345678"), token))
      << "one character short";
  EXPECT_TRUE(ack_refusal(request("POST", "/ack?token=s3cret-token-01234567890"), token))
      << "one character long";
  EXPECT_FALSE(
      ack_refusal(request("POST", "/ack?actuator=cyl&token=s3cret-token-0123456789"), token));
  // Percent-escapes and `+` are decoded once, by the transport's parser.
  EXPECT_FALSE(
      ack_refusal(request("POST", "/ack?token=s3cret%2Dtoken-0123456789&actuator=cyl"), token));
  EXPECT_FALSE(
      ack_refusal(request("POST", "/ack?token=another-token-of-16%2B"), "another-token-of-16+"));
  EXPECT_FALSE(ack_refusal(request("POST", "/ack?token=two+words%20here"), "two words here"));
  EXPECT_TRUE(
      ack_refusal(request("POST", "/ack?token=another-token-of-16+"), "another-token-of-16+"))
      << "a raw + is a space in a query";
  // The token may come as a bearer credential instead.
  http::HttpRequest bearer = request("POST", "/ack?actuator=cyl");
  bearer.authorization = "Bearer " + token;
  EXPECT_FALSE(ack_refusal(bearer, token));
  bearer.authorization = "Basic " + token;
  EXPECT_TRUE(ack_refusal(bearer, token));
  // A malformed escape or a control character never reaches the check: the transport answers
  // 400 for the target (http_target_test, fuzz/http_target_fuzz.cpp).
  EXPECT_FALSE(http::parse_request_target("/ack?token=%zz").target.has_value());
  EXPECT_FALSE(http::parse_request_target("/ack?token=a%0Ab").target.has_value());
}

TEST(DaemonRoutes, TokensCompareInConstantTime) {
  EXPECT_TRUE(same_token("abc", "abc"));
  EXPECT_FALSE(same_token("abd", "abc"));
  EXPECT_FALSE(same_token("ab", "abc"));
  EXPECT_FALSE(same_token("abcd", "abc"));
  EXPECT_FALSE(same_token("", "abc"));
  EXPECT_TRUE(same_token("", ""));
}

TEST(DaemonRoutes, StatusFormatFromParameterOrAccept) {
  EXPECT_FALSE(status_format(request("GET", "/status")).text);
  EXPECT_TRUE(status_format(request("GET", "/status?format=text")).text);
  EXPECT_FALSE(status_format(request("GET", "/status?format=json")).text);
  http::HttpRequest plain = request("GET", "/status");
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

}  // namespace
}  // namespace leakmon::daemon
