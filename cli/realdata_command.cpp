// `leakmon realdata`: the wavelet index on real actuators, the vtnsi data set
// (../shared/data/vtnsi_actuator, README there). The analysis and the data set's layout (which
// folders, which pairs) are study/realdata.hpp; this front end parses the options, runs it on
// the layout and writes strokes.csv, realdata.json and realdata.md into --out.
#include <fmt/format.h>
#include <fmt/os.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "study/realdata.hpp"

namespace leakmon::cli {

int run_realdata(int argc, char** argv) {
  ArgParser args("realdata",
                 "The paper's index on the vtnsi real-actuator data set: per-stroke features,\n"
                 "separation (AUC) of the leaking unit from its healthy pair and of the gear-\n"
                 "damaged unit from its pair, and what the paper's index-drop rule flags.");
  args.option("data", "DIR", "the data set (folders Act_1 .. Act_4_seal_defect)", std::nullopt,
              true)
      .option("out", "DIR", "output directory", std::nullopt, true)
      .option("baseline-quantile", "Q",
              "the paper's rule flags strokes whose index is below this quantile of the "
              "healthy pair's",
              "0.05");
  if (!args.parse(argc, argv)) return 0;
  const std::filesystem::path data = args.get("data");
  const std::filesystem::path out = args.get("out");
  const double q = args.get_double("baseline-quantile");
  if (!(q > 0.0 && q < 1.0)) throw UsageError("option '--baseline-quantile': must be in (0, 1)");
  if (!std::filesystem::is_directory(data)) {
    throw std::runtime_error(fmt::format("{}: not a directory", data.string()));
  }
  std::filesystem::create_directories(out);

  const study::RealdataResult result = study::analyse_realdata(data, study::vtnsi_layout(), q);
  study::write_strokes_csv(out / "strokes.csv", result);
  study::write_realdata_json(out / "realdata.json", result);
  const std::string md = study::realdata_markdown(result);
  auto md_file = fmt::output_file((out / "realdata.md").string());
  md_file.print("{}", md);
  md_file.close();
  fmt::print("{}", md);
  return 0;
}

}  // namespace leakmon::cli
