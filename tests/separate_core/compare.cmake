# Runs the inline and the separate-core builds of the check and fails unless both succeed with the
# same output. -DINLINE=<exe> -DSEPARATE=<exe>
execute_process(COMMAND ${INLINE} OUTPUT_VARIABLE a RESULT_VARIABLE ra)
execute_process(COMMAND ${SEPARATE} OUTPUT_VARIABLE b RESULT_VARIABLE rb)
message(STATUS "inline:\n${a}separate:\n${b}")
if(NOT ra EQUAL 0 OR NOT rb EQUAL 0)
  message(FATAL_ERROR "a build of the check failed (inline ${ra}, separate ${rb})")
endif()
if(NOT a STREQUAL b)
  message(FATAL_ERROR "the inline and the separate-core builds answer differently")
endif()
