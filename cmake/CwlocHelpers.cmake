# Small helpers so every module declares itself the same way.

set(CWLOC_WARNINGS -Wall -Wextra -Wpedantic -Wshadow -Wno-unused-parameter)
# A warning fails the build in CI (.ci/run sets CI=true), so none creeps in; elsewhere it is
# printed, since another compiler version may add warnings of its own.
option(CWLOC_WERROR "Treat warnings as errors (default: on when the environment sets CI)" "$ENV{CI}")
if(CWLOC_WERROR)
  list(APPEND CWLOC_WARNINGS -Werror)
endif()
# The same index gives the same poses on every platform: no fused multiply-adds, which GCC and
# clang make of a * b + c wherever the target has them (aarch64; x86-64 only with -mfma).
set(CWLOC_COMPILE_OPTIONS ${CWLOC_WARNINGS} -ffp-contract=off)

# cwloc_add_library(NAME [SHARED|INTERFACE] SRCS a.cc b.cc PUBLIC_LINK x y PRIVATE_LINK z): static
# unless SHARED. An INTERFACE library is header-only: SRCS lists its headers, PUBLIC_LINK what
# they need, and it has no PRIVATE_LINK (tools/check_layering.py reads the same call).
function(cwloc_add_library name)
  cmake_parse_arguments(ARG "SHARED;INTERFACE" "" "SRCS;PUBLIC_LINK;PRIVATE_LINK" ${ARGN})
  if(ARG_INTERFACE)
    if(ARG_SHARED OR ARG_PRIVATE_LINK)
      message(FATAL_ERROR "cwloc_add_library(${name} INTERFACE): no SHARED and no PRIVATE_LINK")
    endif()
    add_library(${name} INTERFACE ${ARG_SRCS})
    target_include_directories(${name} INTERFACE ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}/generated)
    target_link_libraries(${name} INTERFACE ${ARG_PUBLIC_LINK})
    return()
  endif()
  if(ARG_SHARED)
    add_library(${name} SHARED ${ARG_SRCS})
  else()
    add_library(${name} STATIC ${ARG_SRCS})
  endif()
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}/generated)
  target_compile_options(${name} PRIVATE ${CWLOC_COMPILE_OPTIONS})
  target_link_libraries(${name} PUBLIC ${ARG_PUBLIC_LINK} PRIVATE ${ARG_PRIVATE_LINK})
endfunction()

# Code that runs little (the tools' mains, the Python bindings; the tests' own code below)
# compiles at -O1 in optimised builds: in less than half the time of -O3 (34 s -> 14 s for a
# typical test file; cwloc-localize's main 22 -> 14 s with GCC), while the libraries it calls keep the build
# type's optimisation. After CMake's -O3 on the command line, so it wins. Under a sanitizer at
# -O0: clang instruments and compiles it in less than half the time of -O1 (66 s -> 29 s for
# localizer_tests; cwloc-index's main 13 s at -O0 against 37 s at -O3, 35 s at -O1).
if(CWLOC_SANITIZE)
  set(CWLOC_LIGHT_CODE_OPTIMISATION -O0)
else()
  set(CWLOC_LIGHT_CODE_OPTIMISATION $<$<CONFIG:Release,RelWithDebInfo>:-O1>)
endif()

# cwloc_add_executable(NAME OUTPUT cwloc-foo SRCS main.cc LINK libs... [BENCHMARK]). A main is
# code that runs little (CWLOC_LIGHT_CODE_OPTIMISATION). A BENCHMARK keeps the build's
# optimisation, but under a sanitizer: it times code it compiles itself (FLANN's headers,
# inline kernels).
function(cwloc_add_executable name)
  cmake_parse_arguments(ARG "BENCHMARK" "OUTPUT" "SRCS;LINK" ${ARGN})
  add_executable(${name} ${ARG_SRCS})
  target_compile_options(${name} PRIVATE ${CWLOC_COMPILE_OPTIONS})
  if(CWLOC_SANITIZE OR NOT ARG_BENCHMARK)
    target_compile_options(${name} PRIVATE ${CWLOC_LIGHT_CODE_OPTIMISATION})
  endif()
  target_link_libraries(${name} PRIVATE ${ARG_LINK})
  if(ARG_OUTPUT)
    set_target_properties(${name} PROPERTIES OUTPUT_NAME ${ARG_OUTPUT})
  endif()
endfunction()

# The tests' own code runs little: -O0 in every build (GCC compiles localizer_tests in 27 s
# instead of 38 s at -O1); a test file whose own code computes its reference keeps -O1
# (cwloc_test_computes_reference). Under AddressSanitizer it is not instrumented either: ASan and
# UBSan watch the code under test (the libraries, the tools the tests run, and every heap block,
# which ASan's allocator guards whoever allocates it), and the tests' own code compiles in about
# half the time; CWLOC_SANITIZED tells it that it runs sanitized (test::kSanitized). GCC's
# -Wmaybe-uninitialized misreads std::optional<std::string> at -O1 (GCC bug 80635).
set(CWLOC_TEST_COMPILE_OPTIONS ${CWLOC_COMPILE_OPTIONS}
  $<$<CONFIG:Release,RelWithDebInfo,MinSizeRel>:-O0> $<$<CXX_COMPILER_ID:GNU>:-Wno-maybe-uninitialized>)
set(CWLOC_TEST_COMPILE_DEFINITIONS "")
if(CWLOC_SANITIZE)
  list(APPEND CWLOC_TEST_COMPILE_DEFINITIONS CWLOC_SANITIZED=1)
  if(CWLOC_SANITIZE MATCHES "address")
    list(APPEND CWLOC_TEST_COMPILE_OPTIONS -fno-sanitize=all)
  endif()
endif()

# cwloc_test_computes_reference(a_test.cc ...): test files whose own code computes a reference
# (brute-force search, double-precision kernels, whole-database scans) keep -O1, where their
# tests would otherwise run several times slower. Such a file then compiles outside its target's
# unity batch.
function(cwloc_test_computes_reference)
  set_source_files_properties(${ARGN} PROPERTIES COMPILE_OPTIONS -O1)
endfunction()

# cwloc_add_test(NAME SRCS a_test.cc LINK libs...): one gtest binary, registered with CTest;
# its tests carry the label NAME (ctest -L kdtree_tests).
function(cwloc_add_test name)
  cmake_parse_arguments(ARG "" "" "SRCS;LINK" ${ARGN})
  add_executable(${name} ${ARG_SRCS})
  target_compile_options(${name} PRIVATE ${CWLOC_TEST_COMPILE_OPTIONS})
  target_compile_definitions(${name} PRIVATE ${CWLOC_TEST_COMPILE_DEFINITIONS})
  target_link_libraries(${name} PRIVATE cwloc_test_main ${ARG_LINK})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  set_property(GLOBAL APPEND PROPERTY CWLOC_TEST_TARGETS ${name})
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
    PROPERTIES SKIP_REGULAR_EXPRESSION "\\[  SKIPPED \\]" LABELS ${name})
endfunction()
