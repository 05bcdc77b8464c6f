# Finds what the Python module (python/, docs/python.md) needs: a Python 3 interpreter with its
# headers, then pybind11 in its FindPython mode. Sets CWLOC_PYTHON_FOUND.
#
# Debian's pybind11 and numpy belong to Debian's /usr/bin/python3; a python3 earlier on PATH
# (pyenv, conda) may have neither, so that one is preferred unless -DPython3_EXECUTABLE names
# another (pip install does: setup.py passes its own interpreter).
if(NOT DEFINED Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python3_EXECUTABLE /usr/bin/python3)
endif()
find_package(Python3 3.8 QUIET COMPONENTS Interpreter Development.Module)
if(Python3_FOUND)
  find_package(pybind11 2.6 CONFIG QUIET)
endif()
if(Python3_FOUND AND pybind11_FOUND)
  set(CWLOC_PYTHON_FOUND ON)
else()
  set(CWLOC_PYTHON_FOUND OFF)
endif()

# cwloc_add_python_module(NAME OUTPUT module SRCS a.cc LINK libs...): a pybind11 extension
# module named `module`, with the project's warnings. The bindings convert arguments and results:
# code that runs little (CWLOC_LIGHT_CODE_OPTIMISATION).
function(cwloc_add_python_module name)
  cmake_parse_arguments(ARG "" "OUTPUT" "SRCS;LINK" ${ARGN})
  pybind11_add_module(${name} MODULE NO_EXTRAS ${ARG_SRCS})
  target_compile_options(${name} PRIVATE ${CWLOC_COMPILE_OPTIONS}
    ${CWLOC_LIGHT_CODE_OPTIMISATION})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PRIVATE ${ARG_LINK})
  set_target_properties(${name} PROPERTIES OUTPUT_NAME ${ARG_OUTPUT}
    CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
endfunction()
