// Fuzzes the DBC-style signal decoder and the per-tick frame decoder with arbitrary layouts and
// frames, including frames whose length byte lies. Invariants beyond "no crash, no UB": a
// signal decodes exactly when the frame carries enough bytes, and an unsigned raw value fits
// in its bit length.
// fuzz-sources: io/can/signal.cpp io/can/frame_decoder.cpp io/can/bus_state.cpp
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fuzz/fuzz_input.hpp"
#include "io/can/bus_state.hpp"
#include "io/can/frame_decoder.hpp"
#include "io/can/signal.hpp"

using namespace leakmon::io::can;
using leakmon::fuzz::FuzzInput;

namespace {

SignalLayout layout_from(FuzzInput& in) {
  SignalLayout s;
  const std::uint8_t flags = in.byte();
  s.byte_order = (flags & 1) ? ByteOrder::motorola : ByteOrder::intel;
  s.is_signed = (flags & 2) != 0;
  s.extended = (flags & 4) != 0;
  s.id = in.u16_little_endian() & (s.extended ? kExtendedIdMask : kStandardIdMask);
  s.start_bit =
      in.u16_little_endian() % 600;  // beyond 511 on purpose: layout_problem must catch it
  s.length = in.byte() % 70;
  s.factor = 1.0 + in.byte();
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  std::vector<SignalDef> defs;
  const unsigned signals = 1 + in.byte() % 8;
  for (unsigned i = 0; i < signals; ++i) {
    SignalDef def;
    def.channel = "s" + std::to_string(i);
    def.layout = layout_from(in);
    def.max_age_ns = in.u16_little_endian();
    if (!layout_problem(def.layout).empty()) continue;
    defs.push_back(def);
  }
  if (defs.empty()) return 0;
  FrameDecoder decoder(defs);
  std::vector<double> values(defs.size());
  std::int64_t now = 0;
  while (in.remaining() > 0) {
    CanFrame frame;
    const std::uint8_t flags = in.byte();
    frame.extended = (flags & 1) != 0;
    frame.remote = (flags & 2) != 0;
    frame.error = (flags & 4) != 0;
    frame.fd = (flags & 8) != 0;
    frame.id = (flags & 16) ? defs[in.byte() % defs.size()].layout.id : in.u16_little_endian();
    if (flags & 16) frame.extended = defs[0].layout.extended;
    frame.length = in.byte();  // may exceed 64: the decoders must not trust it
    in.take(frame.data.data(), std::min<std::size_t>(frame.data.size(), frame.length));
    for (const auto& def : defs) {
      double value = 0;
      const bool decoded = decode(def.layout, frame, value);
      const bool should = !frame.error && !frame.remote && frame.id == def.layout.id &&
                          frame.extended == def.layout.extended &&
                          frame.length >= bytes_needed(def.layout);
      if (decoded != should) __builtin_trap();
      if (decoded && !def.layout.is_signed && def.layout.length < 64) {
        const auto raw = static_cast<std::uint64_t>(extract_raw(def.layout, frame));
        if (raw >> def.layout.length) __builtin_trap();
      }
    }
    if (frame.error) interpret_error_frame(frame);
    now += in.byte();
    decoder.apply(frame, now);
    decoder.sample(values, now + in.byte());
  }
  return 0;
}
