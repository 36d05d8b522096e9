// Running the leakmon binary from a test and reading what it wrote: the helpers the CLI tests
// share.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace leakmon::test {

// Runs the binary with `args`, stdout and stderr into DIR/leakmon.log; its exit code (-1 when it
// did not exit normally).
int run_leakmon(const std::string& args, const std::string& dir);

// A whole file as text ("" when it cannot be opened).
std::string read_text(const std::string& path);

// One row of a tab-separated table with a header line, by column name.
using TsvRow = std::map<std::string, std::string>;
std::vector<TsvRow> read_tsv(const std::string& path);

}  // namespace leakmon::test
