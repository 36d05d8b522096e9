# Warnings for leakmon's own code; third-party headers come in as SYSTEM. They are errors when
# LEAKMON_WERROR says so (AUTO: in builds with the tests, i.e. development and CI; not in a
# user's or packager's build, which a newer compiler's new warning must not stop).
if(LEAKMON_WERROR STREQUAL "AUTO")
  set(leakmon_warnings_are_errors ${BUILD_TESTING})
else()
  set(leakmon_warnings_are_errors ${LEAKMON_WERROR})
endif()
set(leakmon_werror "")
if(leakmon_warnings_are_errors)
  set(leakmon_werror -Werror)
endif()
add_library(leakmon_warnings INTERFACE)
target_compile_options(leakmon_warnings INTERFACE
  -Wall -Wextra -Wpedantic ${leakmon_werror} -Wshadow -Wnon-virtual-dtor -Wold-style-cast
  -Wcast-align -Woverloaded-virtual -Wnull-dereference -Wimplicit-fallthrough)
