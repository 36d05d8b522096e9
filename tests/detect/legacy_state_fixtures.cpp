// Writes tests/detect/data/legacy_states/ (see legacy_state_cases.hpp): for each case, the state
// the detector exports at the cut, and what a detector of the same build decides after
// importing it. Not part of the build: it is compiled against the build whose layouts the
// fixtures keep (commit 7601cd5, the last before issue 26), e.g. from a checkout of it with
// `cmake --build build --target leakmon_detect` done:
//
//   g++ -std=c++20 -O2 -I. -I$NEW/ -isystem /usr/include/eigen3 \
//       $NEW/tests/detect/legacy_state_fixtures.cpp build/detect/libleakmon_detect.a \
//       build/sim/libleakmon_sim.a build/dsp/libleakmon_dsp.a build/config/libleakmon_config.a \
//       -lyaml-cpp -lfmt -o /tmp/legacy_state_fixtures
//   /tmp/legacy_state_fixtures $NEW/tests/detect/data/legacy_states
//
// (-I$NEW for tests/detect/legacy_state_cases.hpp, which the old tree does not have; its
// synthetic rigs and the detector interface are the same in both.)
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "tests/detect/legacy_state_cases.hpp"

int main(int argc, char** argv) {
  using namespace leakmon;
  if (argc != 2) {
    std::cerr << "usage: legacy_state_fixtures OUT_DIR\n";
    return 2;
  }
  const std::string out = argv[1];
  for (const auto& c : test::legacy_cases()) {
    test::LegacyStream stream(c);
    auto running = test::make_legacy_detector(c);
    detect::Observation o = stream.next();
    while (o.t < c.cut) {
      running->update(o);
      o = stream.next();
    }
    const std::string state = running->export_state().text();
    auto restored = test::make_legacy_detector(c);
    restored->import_state(detect::DetectorState::parse(state));
    std::vector<std::string> lines;
    for (; o.t < c.end; o = stream.next()) {
      lines.push_back(test::decision_line(o, restored->update(o)));
    }
    std::ofstream(out + "/" + c.name + ".state") << state;
    std::ofstream decisions(out + "/" + c.name + ".decisions");
    decisions << "hash " << test::lines_hash(lines) << "\nhops " << lines.size() << "\n";
    for (std::size_t i = 0; i < lines.size(); i += test::kSampleEvery) {
      decisions << i << ' ' << lines[i] << '\n';
    }
    std::cout << c.name << ": " << state.size() << " bytes of state, " << lines.size()
              << " decisions\n";
  }
  return 0;
}
