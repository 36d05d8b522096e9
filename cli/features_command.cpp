// `leakmon features`: the sliding-window wavelet index of one capture channel, as FORMATS.md
// specifies. The capture is read in chunks of rows and each chunk goes through BlockFeatures,
// which gives the same windows and values as the daemon's StreamingFeatures (tests/dsp check
// both against the batch transform and PyWavelets) several windows at a time; captures larger
// than memory work.
#include <fmt/format.h>

#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "capture/capture.hpp"
#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "dsp/block_features.hpp"
#include "dsp/streaming_features.hpp"

namespace leakmon::cli {
namespace {

std::size_t positive_size(const ArgParser& args, std::string_view name) {
  const long long value = args.get_int(name);
  if (value < 1)
    throw UsageError(fmt::format("option '--{}': must be at least 1, got {}", name, value));
  return static_cast<std::size_t>(value);
}

dsp::FeatureParams feature_params(const ArgParser& args) {
  dsp::FeatureParams params;
  params.wavelet = args.get("wavelet");
  params.level = static_cast<int>(args.get_int("level"));
  params.window = positive_size(args, "window");
  params.step = positive_size(args, "step");
  try {
    params.mode = dsp::parse_mode(args.get("mode"));
    dsp::validate(params);
  } catch (const std::invalid_argument& e) {
    throw UsageError(fmt::format("--{}", e.what()));  // messages start with the parameter name
  }
  return params;
}

}  // namespace

int run_features(int argc, char** argv) {
  ArgParser args("features",
                 "Writes the sliding-window wavelet index of one capture channel as CSV `t,rms`:\n"
                 "one row per window (first window = samples 0..window-1, then every step\n"
                 "samples); t is the time of the window's last sample; rms is the root mean\n"
                 "square of the level-`level` detail coefficients of\n"
                 "pywt.wavedec(window, wavelet, mode=mode, level=level). A window containing a\n"
                 "gap gives an empty rms.");
  args.option("in", "CAPTURE.csv", "capture to read (FORMATS.md capture CSV)", std::nullopt, true)
      .option("channel", "NAME", "column to analyse, e.g. p1", std::nullopt, true)
      .option("out", "FEATURES.csv", "where to write the features", std::nullopt, true)
      .option("wavelet", "NAME", "haar, db1..db20, sym2..sym20, coif1..coif5", "db8")
      .option("level", "N", "decomposition level of the detail coefficients", "2")
      .option("window", "SAMPLES", "window length", "400")
      .option("step", "SAMPLES", "samples between window starts", "20")
      .option("mode", "MODE",
              "extension mode, PyWavelets' names: zero, constant, symmetric, reflect, periodic, "
              "smooth, periodization, antisymmetric, antireflect",
              "symmetric");
  if (!args.parse(argc, argv)) return 0;
  const dsp::FeatureParams params = feature_params(args);

  const std::string in_path = args.get("in");
  const std::string channel = args.get("channel");
  capture::CaptureReader reader(in_path);
  const auto column = reader.column_index(channel);
  if (!column) {
    std::string present;
    for (const auto& name : reader.columns()) present += (present.empty() ? "" : ", ") + name;
    throw capture::CaptureError(
        fmt::format("{}: no column '{}' (columns: {})", in_path, channel, present));
  }

  const std::string out_path = args.get("out");
  std::ofstream out(out_path, std::ios::trunc);
  if (!out) throw std::runtime_error(fmt::format("{}: cannot open for writing", out_path));
  std::string text = "t,rms\n";

  dsp::BlockFeatures features(params);
  std::vector<double> row(reader.columns().size());
  // One chunk of the channel and its times: a window completes while its last sample's chunk is
  // being pushed, so its time is in `times`.
  constexpr std::size_t kChunk = 8192;
  std::vector<double> samples;
  std::vector<double> times;
  samples.reserve(kChunk);
  times.reserve(kChunk);
  std::uint64_t chunk_first = 0;
  std::uint64_t windows = 0;
  std::uint64_t gap_windows = 0;
  auto write_window = [&](const dsp::WindowFeature& f) {
    capture::append_number(text, times[f.last_sample - chunk_first]);
    text += ',';
    if (f.feature.valid) {
      capture::append_number(text, f.feature.rms);
    } else {
      ++gap_windows;
    }
    text += '\n';
    ++windows;
  };
  bool more = true;
  while (more) {
    samples.clear();
    times.clear();
    while (samples.size() < kChunk && (more = reader.next(row))) {
      samples.push_back(row[*column]);
      times.push_back(row[reader.t_index()]);
    }
    features.push_block(samples, write_window);
    chunk_first += samples.size();
    if (text.size() > (1u << 16)) {
      out << text;
      text.clear();
    }
  }
  out << text;
  out.close();
  if (!out) throw std::runtime_error(fmt::format("{}: write failed", out_path));
  fmt::print("wrote {} windows ({} with gaps) of {} {} level {} to {}\n", windows, gap_windows,
             channel, params.wavelet, params.level, out_path);
  return 0;
}

}  // namespace leakmon::cli
