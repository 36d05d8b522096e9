# Warnings are errors for leakmon's own code; third-party headers come in as SYSTEM.
add_library(leakmon_warnings INTERFACE)
target_compile_options(leakmon_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Werror -Wshadow -Wnon-virtual-dtor -Wold-style-cast
  -Wcast-align -Woverloaded-virtual -Wnull-dereference -Wimplicit-fallthrough)
