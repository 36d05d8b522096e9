// Every subcommand of the `leakmon` binary: `int run_X(int argc, char** argv)` receives argv
// with argv[0] the subcommand's name, so ArgParser::parse(argc, argv) starts at its options.
#pragma once

namespace leakmon::cli {

int run_features(int argc, char** argv);
int run_model(int argc, char** argv);
int run_sim(int argc, char** argv);
int run_evaluate(int argc, char** argv);
int run_realdata(int argc, char** argv);
int run_run(int argc, char** argv);
int run_replay(int argc, char** argv);
int run_check_config(int argc, char** argv);
int run_probe(int argc, char** argv);
int run_status(int argc, char** argv);
int run_ack(int argc, char** argv);
int run_state(int argc, char** argv);
int run_learn(int argc, char** argv);

}  // namespace leakmon::cli
