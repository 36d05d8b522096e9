// The paper's two position controllers (MODEL.md "Controllers"): a two-degree-of-freedom loop
// u = sat(G(s) (F(s) r - x)), G and F discretised by Tustin at the sample rate, the output
// clipped at +-u_max (no anti-windup, as the paper's controllers have none).
#pragma once

#include <string_view>

#include "sim/transfer_function.hpp"

namespace leakmon::sim {

enum class ControllerKind { basic, fault_tolerant };
std::string_view to_string(ControllerKind kind);
// "basic" or "fault_tolerant" (also "fault-tolerant"); throws std::invalid_argument otherwise.
ControllerKind controller_kind_from_string(std::string_view name);

class Controller {
 public:
  Controller(ControllerKind kind, double sample_rate_hz, double u_max = 10.0);

  // One sample: reference and measured position in, saturated command [V] out.
  double update(double xref, double x_measured) noexcept;
  void reset() noexcept;

  ControllerKind kind() const { return kind_; }
  // The prefiltered reference F(s) r of the last update.
  double filtered_reference() const { return filtered_reference_; }

 private:
  ControllerKind kind_;
  double u_max_;
  DiscreteTransferFunction prefilter_;  // F(s)
  DiscreteTransferFunction feedback_;   // G(s)
  double filtered_reference_ = 0.0;
};

}  // namespace leakmon::sim
