// The daemon's status as JSON (GET /status; schema in docs/daemon.md) and the human summary
// made from that JSON, the one `leakmon status` and GET /status?format=text print. A value that
// is not known yet (no decision, no leak estimate) is JSON null and reads "n/a", never NaN.
#pragma once

#include <string>
#include <string_view>

namespace leakmon::views {

// A JSON number, or null for NaN and infinities (JSON has neither).
std::string json_number(double value);

// The human summary of a /status JSON document. Throws std::runtime_error when `json` is not
// one (names what is missing).
std::string status_text_from_json(std::string_view json);

}  // namespace leakmon::views
