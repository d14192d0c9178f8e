# clogscope_library(NAME [OWN_UNITS] SOURCES file... [PUBLIC dep...] [PRIVATE dep...]): one module's
# static library, clogscope_NAME built from SOURCES, its alias clogscope::NAME (what dependents
# link) and its dependencies, those in PUBLIC passed on to its dependents.
#
# The sources are compiled as unity builds (CMake's UNITY_BUILD: batches of up to
# CLOGSCOPE_UNITY_BATCH files, each batch one translation unit): most of a file's compile time is
# the headers it shares with its neighbours (nlohmann/json, CLI11, spdlog, OpenCV, Eigen) and the
# templates they instantiate, paid once per batch instead of once per file. In Release apps/
# compiled in 54 CPU-s where its 17 files took 212, pipeline/ in 56 where its 14 took 102. Within a
# batch, a helper in an unnamed namespace that two files define alike is a compile error (four
# turned up and each got one home); an overload of the same name or a using-directive at file
# scope is not, and reaches the files after it: name helpers for what they do and keep
# using-directives inside functions. OWN_UNITS keeps one translation unit per source: the
# measurement's libraries (vision/), whose speed is benchmarked per file's code generation and
# whose longest files are their own Eigen fits, which a batch would not shorten.
set(CLOGSCOPE_UNITY_BATCH 8)
function(clogscope_library name)
  cmake_parse_arguments(ARG "OWN_UNITS" "" "SOURCES;PUBLIC;PRIVATE" ${ARGN})
  if(ARG_UNPARSED_ARGUMENTS OR NOT ARG_SOURCES)
    message(FATAL_ERROR
            "clogscope_library(${name}): OWN_UNITS, SOURCES, PUBLIC and PRIVATE lists only")
  endif()
  add_library(clogscope_${name} ${ARG_SOURCES})
  add_library(clogscope::${name} ALIAS clogscope_${name})
  target_link_libraries(clogscope_${name} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
  if(NOT ARG_OWN_UNITS)
    clogscope_unity_build(clogscope_${name})
  endif()
endfunction()

# clogscope_unity_build(TARGET): TARGET's sources in unity batches (see above).
function(clogscope_unity_build target)
  set_target_properties(${target} PROPERTIES UNITY_BUILD ON
                                             UNITY_BUILD_BATCH_SIZE ${CLOGSCOPE_UNITY_BATCH})
endfunction()
