#include "sim/controller.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace leakmon::sim {
namespace {

// MODEL.md "Controllers (from the paper)".
// basic: G(s) = 2.76e6 (s + 25) / ((s + 16)(s^2 + 108 s + 120^2)), F(s) = 100 / (s + 100);
//   (s + 16)(s^2 + 108 s + 14400) = s^3 + 124 s^2 + 16128 s + 230400.
// fault tolerant: G(s) = (246.59 s^3 + 7.18e3 s^2 + 4.78e7 s + 5.49e8) / (s^3 + 420 s^2 + 9e4 s),
//   F(s) = (22.04 s + 297.5) / (s^2 + 43.5 s + 297.5).
DiscreteTransferFunction feedback_for(ControllerKind kind, double fs) {
  if (kind == ControllerKind::basic) {
    return DiscreteTransferFunction::tustin({2.76e6, 2.76e6 * 25.0},
                                            {1.0, 124.0, 16128.0, 230400.0}, fs);
  }
  return DiscreteTransferFunction::tustin({246.59, 7.18e3, 4.78e7, 5.49e8}, {1.0, 420.0, 9e4, 0.0},
                                          fs);
}

DiscreteTransferFunction prefilter_for(ControllerKind kind, double fs) {
  if (kind == ControllerKind::basic)
    return DiscreteTransferFunction::tustin({100.0}, {1.0, 100.0}, fs);
  return DiscreteTransferFunction::tustin({22.04, 297.5}, {1.0, 43.5, 297.5}, fs);
}

}  // namespace

std::string_view to_string(ControllerKind kind) {
  return kind == ControllerKind::basic ? "basic" : "fault_tolerant";
}

ControllerKind controller_kind_from_string(std::string_view name) {
  if (name == "basic") return ControllerKind::basic;
  if (name == "fault_tolerant" || name == "fault-tolerant") return ControllerKind::fault_tolerant;
  throw std::invalid_argument("unknown controller '" + std::string(name) +
                              "' (expected basic or fault_tolerant)");
}

Controller::Controller(ControllerKind kind, double sample_rate_hz, double u_max)
    : kind_(kind),
      u_max_(u_max),
      prefilter_(prefilter_for(kind, sample_rate_hz)),
      feedback_(feedback_for(kind, sample_rate_hz)) {}

double Controller::update(double xref, double x_measured) noexcept {
  filtered_reference_ = prefilter_.update(xref);
  // No anti-windup: the paper's loops only clip their output.
  return std::clamp(feedback_.update(filtered_reference_ - x_measured), -u_max_, u_max_);
}

void Controller::reset() noexcept {
  prefilter_.reset();
  feedback_.reset();
  filtered_reference_ = 0.0;
}

}  // namespace leakmon::sim
