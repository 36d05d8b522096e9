// The `type: mqtt` output's configuration: defaults, and mistakes reported at file:line:column
// with the field's path (what `leakmon check-config` prints).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "io/mqtt/mqtt_output.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::io::mqtt {
namespace {

MqttSettings parse(const std::string& yaml) {
  return parse_mqtt_settings(config::ConfigNode::load_string(yaml, "/etc/leakmon/leakmon.yaml"));
}

std::string error_of(const std::string& yaml) {
  try {
    parse(yaml);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(MqttConfig, DefaultsFollowTheTopic) {
  const auto s = parse("{name: fleet, type: mqtt, topic: leakmon/lab/rig1}");
  EXPECT_EQ(s.host, "127.0.0.1");
  EXPECT_EQ(s.port, 1883);
  EXPECT_EQ(s.client_id, "leakmon-leakmon-lab-rig1");
  EXPECT_EQ(s.keepalive_s, 30);
  EXPECT_DOUBLE_EQ(s.features_hz, 1.0);
  EXPECT_EQ(s.queue_limits.max_events, 10000u);
  EXPECT_NE(s.queue_directory.find("mqtt-fleet"), std::string::npos);
  EXPECT_FALSE(s.tls.enabled);
}

TEST(MqttConfig, FieldsAndRelativeQueueDirectory) {
  const auto s = parse(
      "{name: fleet, type: mqtt, host: broker.lan, port: 1884, topic: a/b, client_id: rig-7,\n"
      " username: u, password: p, keepalive_s: 10, features_hz: 5,\n"
      " queue: {directory: q, max_events: 50, max_bytes: 100000}}");
  EXPECT_EQ(s.host, "broker.lan");
  EXPECT_EQ(s.port, 1884);
  EXPECT_EQ(s.client_id, "rig-7");
  EXPECT_EQ(s.username, "u");
  EXPECT_EQ(s.password, "p");
  EXPECT_EQ(s.queue_directory, "/etc/leakmon/q");
  EXPECT_EQ(s.queue_limits.max_events, 50u);
  EXPECT_EQ(s.queue_limits.max_bytes, 100000u);
}

TEST(MqttConfig, TlsFilesMustExistAndTheDefaultPortBecomes8883) {
  const std::string dir = test::scratch_dir("mqtt_config_tls");
  std::ofstream(dir + "/ca.crt") << "x";
  std::ofstream(dir + "/client.crt") << "x";
  std::ofstream(dir + "/client.key") << "x";
  const auto s =
      parse("{name: f, type: mqtt, topic: a, tls: {ca_file: " + dir + "/ca.crt, cert_file: " + dir +
            "/client.crt, key_file: " + dir + "/client.key}}");
  EXPECT_TRUE(s.tls.enabled);
  EXPECT_EQ(s.port, 8883);
  EXPECT_EQ(s.tls.key_file, dir + "/client.key");

  EXPECT_NE(error_of("{name: f, type: mqtt, topic: a, tls: {ca_file: " + dir + "/missing.crt}}")
                .find("does not exist or is not readable"),
            std::string::npos);
  EXPECT_NE(error_of("{name: f, type: mqtt, topic: a, tls: {ca_file: " + dir +
                     "/ca.crt, cert_file: " + dir + "/client.crt}}")
                .find("needs both cert_file and key_file"),
            std::string::npos);
  EXPECT_NE(error_of("{name: f, type: mqtt, topic: a, tls: {}}").find("needs ca_file"),
            std::string::npos);
}

TEST(MqttConfig, MistakesNameFileLineAndColumn) {
  const std::string unknown = error_of("name: f\ntype: mqtt\ntopic: a\nhots: x\n");
  EXPECT_NE(unknown.find("/etc/leakmon/leakmon.yaml:4:"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("hots"), std::string::npos) << unknown;

  const std::string wildcard = error_of("name: f\ntype: mqtt\ntopic: leakmon/+/rig\n");
  EXPECT_NE(wildcard.find("leakmon.yaml:3:8"), std::string::npos) << wildcard;
  EXPECT_NE(wildcard.find("wildcards"), std::string::npos) << wildcard;

  EXPECT_NE(error_of("{name: f, type: mqtt}").find("topic"), std::string::npos);
  EXPECT_NE(error_of("{name: f, type: mqtt, topic: a/}").find("end with '/'"), std::string::npos);
  EXPECT_NE(error_of("{name: f, type: mqtt, topic: a, password: p}").find("needs a username"),
            std::string::npos);
  EXPECT_NE(error_of("{name: f, type: mqtt, topic: a, port: 70000}").find("port"),
            std::string::npos);
  EXPECT_NE(error_of("{name: f, type: mqtt, topic: a, queue: {max_events: 0}}").find("max_events"),
            std::string::npos);
  EXPECT_NE(error_of("{name: f, type: mqtt, topic: a, features_hz: 100}").find("features_hz"),
            std::string::npos);
}

// Issue 25: the password kept out of the configuration, in a root-only file or a systemd
// credential (LoadCredential=NAME:PATH puts it at $CREDENTIALS_DIRECTORY/NAME).
TEST(MqttConfig, PasswordFromAFileOrASystemdCredential) {
  const std::string dir = test::scratch_dir("mqtt_config_password_file");
  const std::string config = dir + "/leakmon.yaml";
  std::ofstream(dir + "/mqtt-password") << "s3cret: with spaces\n";
  const auto in_file = [&](const std::string& yaml) {
    return parse_mqtt_settings(config::ConfigNode::load_string(yaml, config));
  };
  ::unsetenv("CREDENTIALS_DIRECTORY");
  // Relative: beside the configuration (check-config by hand reads what the unit's
  // LoadCredential reads), one trailing newline dropped.
  EXPECT_EQ(in_file("{name: f, type: mqtt, topic: a, username: u, password_file: mqtt-password}")
                .password,
            "s3cret: with spaces");
  EXPECT_EQ(in_file("{name: f, type: mqtt, topic: a, username: u, password_file: " + dir +
                    "/mqtt-password}")
                .password,
            "s3cret: with spaces");
  // Under systemd with credentials: the relative name is the credential's.
  const std::string credentials = dir + "/credentials";
  std::filesystem::create_directories(credentials);
  std::ofstream(credentials + "/mqtt-password") << "from-systemd";
  ::setenv("CREDENTIALS_DIRECTORY", credentials.c_str(), 1);
  EXPECT_EQ(in_file("{name: f, type: mqtt, topic: a, username: u, password_file: mqtt-password}")
                .password,
            "from-systemd");
  ::unsetenv("CREDENTIALS_DIRECTORY");

  // The inline password stays accepted; not both; a missing or empty file names its field.
  EXPECT_EQ(parse("{name: f, type: mqtt, topic: a, username: u, password: p}").password, "p");
  const std::string both =
      error_of("name: f\ntype: mqtt\ntopic: a\nusername: u\npassword: p\npassword_file: /x\n");
  EXPECT_NE(both.find("leakmon.yaml:5:11: password: give either password or password_file"),
            std::string::npos)
      << both;
  try {
    in_file("name: f\ntype: mqtt\ntopic: a\nusername: u\npassword_file: nowhere\n");
    ADD_FAILURE() << "a missing password file was accepted";
  } catch (const config::ConfigError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(config + ":5:16: password_file: cannot read '" + dir + "/nowhere'"),
              std::string::npos)
        << message;
  }
  std::ofstream(dir + "/empty");
  EXPECT_THROW(in_file("{name: f, type: mqtt, topic: a, username: u, password_file: empty}"),
               config::ConfigError);
  EXPECT_NE(error_of("{name: f, type: mqtt, topic: a, password_file: /x}").find("needs a username"),
            std::string::npos);
}

TEST(MqttConfig, TheBrokerHostIsAnAddressOrAName) {
  EXPECT_EQ(parse("{name: f, type: mqtt, topic: a, host: broker.plant-a.lan}").host,
            "broker.plant-a.lan");
  EXPECT_EQ(parse("{name: f, type: mqtt, topic: a, host: '::1'}").host, "::1");
  const std::string bad = error_of("name: f\ntype: mqtt\ntopic: a\nhost: 10.0.0.256\n");
  EXPECT_NE(bad.find("leakmon.yaml:4:7: host: '10.0.0.256' is not an IPv4 address"),
            std::string::npos)
      << bad;
  EXPECT_NE(error_of("{name: f, type: mqtt, topic: a, host: 'broker lan'}").find("host name"),
            std::string::npos);
}

TEST(MqttConfig, TopicLevelsCannotSplitOrMatch) {
  EXPECT_EQ(topic_level("cyl/1+#"), "cyl_1__");
  EXPECT_EQ(topic_level("cylinder"), "cylinder");
}

}  // namespace
}  // namespace leakmon::io::mqtt
