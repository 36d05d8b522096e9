// Every subcommand of the `leakmon` binary: `int run_X(int argc, char** argv)` receives argv
// with argv[0] the subcommand's name, so ArgParser::parse(argc, argv) starts at its options.
#pragma once

namespace leakmon::cli {

int run_features(int argc, char** argv);

}  // namespace leakmon::cli
