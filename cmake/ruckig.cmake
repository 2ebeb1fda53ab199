# ruckig's C++ sources, the same release as the Python oracle and benchmark:
# the version host_tools/constraints.txt pins (ruckig==V, its one home), from
# its sdist, which .ci/setup fetches with the registry's own client (pip
# download --no-binary :all: --no-deps ruckig==V, which knows its index and
# this machine's settings) into .deps/. The configure never downloads: it
# checks the file against the sdist's SHA256 below and extracts it into the
# build tree. Defines the static library ls_ruckig (the state-to-state solver
# only; ls_otg in firmware/motion is its C API).
#
#   -DLS_RUCKIG_SDIST=/path/to/ruckig-V.tar.gz   use this file
#   default: ${LS_DEPS_DIR}/ruckig-V.tar.gz; LS_DEPS_DIR defaults to .deps/ in
#   the source tree, shared by every build dir.
get_filename_component(ls_ruckig_root "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
file(STRINGS "${ls_ruckig_root}/host_tools/constraints.txt" ls_ruckig_pin REGEX "^ruckig==")
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${ls_ruckig_root}/host_tools/constraints.txt")
string(REGEX REPLACE "^ruckig==([0-9.]+).*$" "\\1" LS_RUCKIG_VERSION "${ls_ruckig_pin}")
if(NOT LS_RUCKIG_VERSION MATCHES "^[0-9]+\\.[0-9]+\\.[0-9]+$")
  message(FATAL_ERROR "ruckig: host_tools/constraints.txt pins no ruckig==X.Y.Z (found '${ls_ruckig_pin}')")
endif()
# The SHA256 of that version's sdist: a new pin fails here until this is its hash.
set(LS_RUCKIG_SHA256 71d003bf0ff9aa0031d4520b0290a5ffa6458149f5afce8be3ed6d6fba49ea64)
set(LS_DEPS_DIR "${ls_ruckig_root}/.deps" CACHE PATH "Where third-party sources are kept (.ci/setup fills it)")
set(LS_RUCKIG_SDIST "${LS_DEPS_DIR}/ruckig-${LS_RUCKIG_VERSION}.tar.gz" CACHE FILEPATH
    "ruckig ${LS_RUCKIG_VERSION} sdist (.ci/setup fetches it with pip download)")

if(NOT EXISTS "${LS_RUCKIG_SDIST}")
  message(FATAL_ERROR "ruckig: ${LS_RUCKIG_SDIST} is missing: run bash .ci/setup (it fetches it with "
                      "pip download --no-binary :all: --no-deps ruckig==${LS_RUCKIG_VERSION} into .deps/), or "
                      "configure with -DLS_RUCKIG_SDIST=/path/to/ruckig-${LS_RUCKIG_VERSION}.tar.gz")
endif()
file(SHA256 "${LS_RUCKIG_SDIST}" ls_ruckig_sha)
if(NOT ls_ruckig_sha STREQUAL LS_RUCKIG_SHA256)
  message(FATAL_ERROR "ruckig: ${LS_RUCKIG_SDIST} has SHA256 ${ls_ruckig_sha}, not the one this tree expects "
                      "(${LS_RUCKIG_SHA256}, cmake/ruckig.cmake). Delete it and run bash .ci/setup again, or "
                      "point -DLS_RUCKIG_SDIST at the genuine ruckig-${LS_RUCKIG_VERSION}.tar.gz; after a new "
                      "pin in host_tools/constraints.txt, set LS_RUCKIG_SHA256 to its sdist's hash")
endif()

set(LS_RUCKIG_DIR "${CMAKE_BINARY_DIR}/_deps/ruckig-${LS_RUCKIG_VERSION}")
if(NOT EXISTS "${LS_RUCKIG_DIR}/.sha256-${LS_RUCKIG_SHA256}")
  file(REMOVE_RECURSE "${LS_RUCKIG_DIR}")
  file(ARCHIVE_EXTRACT INPUT "${LS_RUCKIG_SDIST}" DESTINATION "${CMAKE_BINARY_DIR}/_deps"
       PATTERNS "ruckig-${LS_RUCKIG_VERSION}/include/*" "ruckig-${LS_RUCKIG_VERSION}/src/*"
                "ruckig-${LS_RUCKIG_VERSION}/LICENSE")
  file(TOUCH "${LS_RUCKIG_DIR}/.sha256-${LS_RUCKIG_SHA256}")
endif()

# The state-to-state solver: the brake pre-trajectory and the position and
# velocity interfaces' two steps. Not cloud_client.cpp (waypoints over HTTP)
# nor the Python binding.
set(ls_ruckig_srcs brake.cpp position_first_step1.cpp position_first_step2.cpp position_second_step1.cpp
    position_second_step2.cpp position_third_step1.cpp position_third_step2.cpp velocity_second_step1.cpp
    velocity_second_step2.cpp velocity_third_step1.cpp velocity_third_step2.cpp)
list(TRANSFORM ls_ruckig_srcs PREPEND "${LS_RUCKIG_DIR}/src/ruckig/")
add_library(ls_ruckig STATIC ${ls_ruckig_srcs})
# SYSTEM: ruckig's headers do not see our -Werror set from our own sources.
target_include_directories(ls_ruckig SYSTEM PUBLIC "${LS_RUCKIG_DIR}/include")
# Third-party code: its own warnings are not ours to fix (-w for these TUs only).
target_compile_options(ls_ruckig PRIVATE -w -fno-exceptions -fno-rtti)
# LS_RUCKIG_DEFINITIONS, for every TU that includes ruckig's headers: ruckig's
# profile.hpp, brake.hpp and calculator_target.hpp include <iostream> though
# nothing but the cloud client (not built) uses a stream object. With GCC < 13
# each such TU then defines a static std::ios_base::Init whose constructor
# builds cout/cin/cerr and their locales: on the Cortex-M image (bench 7) that
# links newlib's allocator and stdio, on Linux it is start-up work for
# nothing. Defining libstdc++'s include guard keeps <iostream> out (<ostream>
# and <istream> still come through <sstream>, for ruckig's to_string helpers);
# a ruckig that used std::cout would fail to compile, not pass silently.
# A definition, not a forced include, so the footprint's manifest carries it.
# _DEFAULT_SOURCE: ruckig's roots.hpp uses M_PI, which newlib (the Cortex-M
# C library) declares only outside strict ISO C++ (g++ on Linux always
# defines _GNU_SOURCE, which implies it).
set(LS_RUCKIG_DEFINITIONS _GLIBCXX_IOSTREAM=1 _DEFAULT_SOURCE)
target_compile_definitions(ls_ruckig PRIVATE ${LS_RUCKIG_DEFINITIONS})
# Numeric third-party code: no coverage feedback under LS_FUZZ (CMakeLists.txt).
ls_fuzz_uninstrumented(ls_ruckig)
