# Fails when an archive (LIBS, ;-separated) references an allocator,
# operator new/delete, the exception machinery or iostream's static init:
# then the code could allocate or throw in the control loop, or drag
# newlib's stdio and allocator into the Cortex-M image.
foreach(lib IN LISTS LIBS)
  execute_process(COMMAND ${NM} -u ${lib} OUTPUT_VARIABLE undefined RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "nm failed on ${lib}")
  endif()
  string(REGEX MATCHALL "[ \t](malloc|calloc|realloc|free|aligned_alloc|posix_memalign|memalign|_Znw[a-zA-Z0-9_]*|_Zna[a-zA-Z0-9_]*|_Zdl[a-zA-Z0-9_]*|_Zda[a-zA-Z0-9_]*|__cxa_throw|__cxa_allocate_exception|_ZNSt8ios_base4InitC1Ev)\n" bad "${undefined}")
  if(bad)
    message(FATAL_ERROR "${lib} references allocation, exception or iostream symbols:${bad}")
  endif()
  message(STATUS "${lib}: no allocator, no exception, no iostream symbol")
endforeach()
