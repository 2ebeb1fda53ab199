# ruckig's C++ sources, the same release as the Python oracle and benchmark
# (host_tools/constraints.txt pins ruckig==0.19.4), from its PyPI sdist: one
# download per machine, checked against the sdist's published SHA256, then
# extracted into the build tree. Defines the static library ls_ruckig (the
# state-to-state solver only; ls_otg in firmware/motion is its C API).
#
#   -DLS_RUCKIG_SDIST=/path/to/ruckig-0.19.4.tar.gz   use this file (offline)
#   default: ${LS_DEPS_DIR}/ruckig-0.19.4.tar.gz, downloaded once when absent;
#   LS_DEPS_DIR defaults to .deps/ in the source tree, shared by every build dir.
set(LS_RUCKIG_VERSION 0.19.4)
set(LS_RUCKIG_SHA256 71d003bf0ff9aa0031d4520b0290a5ffa6458149f5afce8be3ed6d6fba49ea64)
set(LS_RUCKIG_URL
    "https://files.pythonhosted.org/packages/4a/2a/d1c1639bf76699ab1c3c1281101372f2b749d0ad8aee4c19200947b92785/ruckig-${LS_RUCKIG_VERSION}.tar.gz")
get_filename_component(ls_ruckig_root "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
set(LS_DEPS_DIR "${ls_ruckig_root}/.deps" CACHE PATH "Where downloaded third-party sources are kept")
set(LS_RUCKIG_SDIST "${LS_DEPS_DIR}/ruckig-${LS_RUCKIG_VERSION}.tar.gz" CACHE FILEPATH
    "ruckig ${LS_RUCKIG_VERSION} sdist (PyPI); downloaded here when absent")

if(NOT EXISTS "${LS_RUCKIG_SDIST}")
  message(STATUS "ruckig: downloading ${LS_RUCKIG_URL}")
  # A name of its own, renamed when complete: configures that run at once
  # (CI's build directories) never read each other's half-written file.
  string(RANDOM LENGTH 8 ls_dl_tag)
  set(ls_dl_part "${LS_RUCKIG_SDIST}.${ls_dl_tag}.part")
  # Where HTTPS goes through a proxy with a CA of its own, SSL_CERT_FILE names
  # the bundle to trust (OpenSSL's convention, which Python follows too);
  # otherwise curl's default, Debian's ca-certificates.
  set(ls_dl_cainfo "")
  if(DEFINED ENV{SSL_CERT_FILE} AND EXISTS "$ENV{SSL_CERT_FILE}")
    set(ls_dl_cainfo TLS_CAINFO "$ENV{SSL_CERT_FILE}")
  endif()
  file(DOWNLOAD "${LS_RUCKIG_URL}" "${ls_dl_part}" STATUS ls_dl_status TLS_VERIFY ON ${ls_dl_cainfo})
  list(GET ls_dl_status 0 ls_dl_code)
  if(NOT ls_dl_code EQUAL 0)
    list(GET ls_dl_status 1 ls_dl_text)
    file(REMOVE "${ls_dl_part}")
    message(FATAL_ERROR "ruckig: could not download ${LS_RUCKIG_URL} (${ls_dl_text}). Offline: fetch "
                        "ruckig-${LS_RUCKIG_VERSION}.tar.gz elsewhere (pip download --no-binary :all: --no-deps "
                        "ruckig==${LS_RUCKIG_VERSION}) and configure with -DLS_RUCKIG_SDIST=/path/to/it")
  endif()
  file(RENAME "${ls_dl_part}" "${LS_RUCKIG_SDIST}")
endif()
file(SHA256 "${LS_RUCKIG_SDIST}" ls_ruckig_sha)
if(NOT ls_ruckig_sha STREQUAL LS_RUCKIG_SHA256)
  message(FATAL_ERROR "ruckig: ${LS_RUCKIG_SDIST} has SHA256 ${ls_ruckig_sha}, not the ${LS_RUCKIG_VERSION} sdist's "
                      "${LS_RUCKIG_SHA256}. Delete it (the next configure downloads it again) or point "
                      "-DLS_RUCKIG_SDIST at the genuine ruckig-${LS_RUCKIG_VERSION}.tar.gz from PyPI")
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
