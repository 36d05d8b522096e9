// The service's snapshot as JSON documents: GET /status (schema in docs/daemon.md), the human
// summary made from that JSON (what `leakmon status` and GET /status?format=text print), and
// the feature message of one actuator that MQTT outputs publish. Field names and units are the
// vocabulary's (views/vocabulary.hpp). A value that is not known yet (no decision, no leak
// estimate) is JSON null in /status and reads "n/a" in the summary, never NaN; a feature
// message leaves it out.
#pragma once

#include <string>
#include <string_view>

#include "views/snapshot.hpp"

namespace leakmon::views {

// GET /status.
std::string status_json(const ServiceSnapshot& snapshot);

// The human summary of a /status JSON document (this version's, or the previous one's field
// names). Throws std::runtime_error when `json` is not one (names what is missing).
std::string status_text_from_json(std::string_view json);

// One actuator's feature message for the MQTT outputs' `TOPIC/<actuator>/features`.
std::string features_json(const ServiceSnapshot& snapshot,
                          const pipeline::ActuatorStatus& actuator);

}  // namespace leakmon::views
