# clogscope_library(NAME SOURCES file... [PUBLIC dep...] [PRIVATE dep...]): one module's static
# library, clogscope_NAME built from SOURCES, its alias clogscope::NAME (what dependents link) and
# its dependencies, those in PUBLIC passed on to its dependents.
function(clogscope_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC;PRIVATE" ${ARGN})
  if(ARG_UNPARSED_ARGUMENTS OR NOT ARG_SOURCES)
    message(FATAL_ERROR "clogscope_library(${name}): SOURCES, PUBLIC and PRIVATE lists only")
  endif()
  add_library(clogscope_${name} ${ARG_SOURCES})
  add_library(clogscope::${name} ALIAS clogscope_${name})
  target_link_libraries(clogscope_${name} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
endfunction()
