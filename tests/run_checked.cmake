# Runs a program and passes its standard output on only if it exits with status 0, so that
# a test's PASS_REGULAR_EXPRESSION (which CTest matches whatever the exit status) cannot
# pass on a program that printed the expected line and then failed: a crash, a sanitizer's
# report at exit, an exception after the line.
#
#   cmake "-DCOMMAND=program|arg|arg" [-DWORKDIR=dir] -P run_checked.cmake
#
# COMMAND separates the arguments with '|' (a ';' would not survive add_test).

if(NOT COMMAND)
  message(FATAL_ERROR "run_checked: pass -DCOMMAND=program|args")
endif()
if(NOT WORKDIR)
  set(WORKDIR .)
endif()
string(REPLACE "|" ";" command "${COMMAND}")
execute_process(
  COMMAND ${command}
  WORKING_DIRECTORY "${WORKDIR}"
  RESULT_VARIABLE status
  OUTPUT_VARIABLE out
  ERROR_VARIABLE err)
if(NOT status STREQUAL "0")
  # The output is withheld: the expected line in it must not pass the test.
  message(FATAL_ERROR "run_checked: ${command} exited with ${status} (its output withheld); stderr:\n${err}")
endif()
message("${out}")
