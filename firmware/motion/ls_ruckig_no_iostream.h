/* Force-included before every TU that includes ruckig's headers.
 *
 * ruckig's profile.hpp, brake.hpp and calculator_target.hpp include
 * <iostream> although nothing but the cloud client (not built) uses a stream
 * object. With GCC < 13 each such TU defines a static std::ios_base::Init,
 * whose constructor builds cout/cin/cerr and their locales: on the Cortex-M
 * image that links newlib's allocator and stdio (bench 7 forbids both), and
 * on Linux it is start-up work for nothing. Marking <iostream> as already
 * included keeps it out; <ostream> and <istream> (the types ruckig's
 * to_string helpers name) still come through <sstream>/<iomanip>. A future
 * ruckig that used std::cout would fail to compile here, not silently. */
#ifndef LS_RUCKIG_NO_IOSTREAM_H
#define LS_RUCKIG_NO_IOSTREAM_H
#ifdef __cplusplus
#define _GLIBCXX_IOSTREAM 1
#endif
#endif
