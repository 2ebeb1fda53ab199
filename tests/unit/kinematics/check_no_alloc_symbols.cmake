# Fails when the kinematics archive references an allocator, operator new or
# the exception machinery: then it could allocate or throw in the control loop.
execute_process(COMMAND ${NM} -u ${LIB} OUTPUT_VARIABLE undefined RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "nm failed on ${LIB}")
endif()
string(REGEX MATCHALL "[ \t](malloc|calloc|realloc|free|aligned_alloc|posix_memalign|memalign|_Znw[a-zA-Z0-9_]*|_Zna[a-zA-Z0-9_]*|__cxa_throw|__cxa_allocate_exception)\n" bad "${undefined}")
if(bad)
  message(FATAL_ERROR "ls_kin references allocation or exception symbols:${bad}")
endif()
message(STATUS "ls_kin references no allocator and no exception symbol")
