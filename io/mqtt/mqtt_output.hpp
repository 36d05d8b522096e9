// The MQTT output (`outputs:` entry with `type: mqtt`, see README.md beside this file): every
// event to a broker at QoS 1 through a durable on-disk queue, a retained online/offline status
// with birth message and last will, and decimated per-actuator features at QoS 0, for a fleet
// view of many rigs. FORMATS.md "Operator view and fleet" fixes the topic names.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "config/yaml_reader.hpp"
#include "io/event.hpp"
#include "io/mqtt/disk_queue.hpp"

namespace leakmon::io::mqtt {

struct TlsSettings {
  bool enabled = false;
  std::string ca_file;  // or ca_path: a directory of hashed CA certificates
  std::string ca_path;
  std::string cert_file;  // client certificate and key, both or neither
  std::string key_file;
};

struct MqttSettings {
  std::string name;
  std::string host = "127.0.0.1";
  int port = 1883;
  std::string topic;  // the rig's root, e.g. leakmon/SITE/RIG
  std::string client_id;
  std::string username;  // empty: anonymous
  std::string password;
  TlsSettings tls;
  int keepalive_s = 30;
  double features_hz = 1.0;  // 0: no features
  double connect_timeout_s = 10.0;
  double reconnect_max_s = 5.0;
  std::string queue_directory;
  DiskQueueLimits queue_limits;
  std::size_t handoff_capacity = 4096;  // events between the worker and the output's thread
};

// Validates the YAML mapping (file:line:column errors); opens nothing.
MqttSettings parse_mqtt_settings(const config::ConfigNode& node);

// MQTT topic level for a name: '/', '+' and '#' (which would split or match levels) become '_'.
std::string topic_level(std::string_view name);

// The output: publish() formats the event and hands it to the output's thread through a
// bounded in-memory queue, never touching the network or the disk. The thread (started with the
// first event, flush or attach, so check-config connects nowhere) appends each event to the
// disk queue, delivers the queue in order (one message in flight; removed on PUBACK), and
// reconnects with backoff.
std::unique_ptr<EventSink> make_mqtt_output(const config::ConfigNode& node);
std::unique_ptr<EventSink> make_mqtt_output_with(MqttSettings settings);

}  // namespace leakmon::io::mqtt
