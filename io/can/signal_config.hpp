// The `signals:` list of a CAN driver's YAML mapping (both `type: can` and `type: canlog`):
//
//   max_age: 0.02            # optional default for every signal, seconds
//   signals:
//     - channel: p1          # channel name the daemon sees
//       id: 0x101            # hex (0x...) or decimal
//       extended: false      # 29-bit identifier
//       start_bit: 0         # DBC numbering (see signal.hpp)
//       length: 16
//       byte_order: intel    # intel | motorola
//       signed: false
//       factor: 5050
//       offset: 0
//       unit: Pa
//       max_age: 0.01        # optional, overrides the driver's
#pragma once

#include <cstdint>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/can/frame_decoder.hpp"

namespace leakmon::io::can {

// Default max age when neither the driver nor the signal sets one: ten 500 Hz periods. A value
// held for longer would flatten the pressure trace, and a flat trace has a low wavelet index,
// which is exactly what a leak looks like: a silent sensor must become a gap, not an alarm.
inline constexpr double kDefaultMaxAgeSeconds = 0.02;

// Reads and validates `driver.signals` (and `driver.max_age`); every error names file, line,
// column and field.
std::vector<SignalDef> read_signals(const config::ConfigNode& driver);

// A CAN identifier written as decimal or 0x-prefixed hex.
std::uint32_t read_can_id(const config::ConfigNode& node);

}  // namespace leakmon::io::can
