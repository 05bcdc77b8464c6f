# Sanitizer and fuzzing builds (docs/reliability.md). Both instrument every target, so they
# need a compiler that supports the requested sanitizers (clang for the fuzzers).
#   -DCWLOC_SANITIZE=address,undefined   ASan + UBSan; every report aborts the process
#   -DCWLOC_SANITIZE=thread              ThreadSanitizer
#   -DCWLOC_BUILD_FUZZERS=ON             libFuzzer targets in fuzz/ (clang only)
set(CWLOC_SANITIZE "" CACHE STRING "Sanitizers for every target: address,undefined or thread")
option(CWLOC_BUILD_FUZZERS "Build the libFuzzer targets in fuzz/ (clang)" OFF)

if(CWLOC_SANITIZE)
  # Symbolized stacks at -O2 without a full -g's compile and link time.
  set(sanitize_flags -fsanitize=${CWLOC_SANITIZE} -fno-omit-frame-pointer)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    list(APPEND sanitize_flags -gline-tables-only)
  else()
    list(APPEND sanitize_flags -g1)
  endif()
  if(CWLOC_SANITIZE MATCHES "undefined")
    # A UBSan finding fails the test or the fuzz run instead of printing and going on.
    list(APPEND sanitize_flags -fno-sanitize-recover=all)
    if(CWLOC_SANITIZE MATCHES "address")
      # Not UBSan's object-size check, which ASan's redzones make redundant, nor its vptr check
      # (dynamic types of polymorphic objects, which the library hardly has): the pose library
      # compiles in 71 s instead of 80 (clang 14, one core).
      list(APPEND sanitize_flags -fno-sanitize=object-size,vptr)
    endif()
  endif()
  add_compile_options(${sanitize_flags})
  add_link_options(-fsanitize=${CWLOC_SANITIZE})
endif()

if(CWLOC_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "CWLOC_BUILD_FUZZERS needs clang (Debian: clang libclang-rt-14-dev): "
      "configure with -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++")
  endif()
endif()
