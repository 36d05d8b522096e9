// Where tests find things: the source tree, the build tree, ../shared/data, scratch space.
#pragma once

#include <string>

namespace leakmon::test {

std::string source_dir();
std::string binary_dir();
std::string leakmon_binary();   // build/bin/leakmon
std::string shared_data_dir();  // ../shared/data beside the clone (LEAKMON_SHARED_DATA overrides)
std::string python();           // /usr/bin/python3: Debian's interpreter, with pywt and numpy
std::string scratch_dir(const std::string& test_name);  // fresh, empty, under the build tree

}  // namespace leakmon::test
