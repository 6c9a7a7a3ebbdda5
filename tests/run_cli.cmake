# Runs the mgrl command line once and checks the stream and exit-code contract of
# app/main.cpp:
#   failure: a non-zero exit (or exactly EXIT), nothing on stdout, exactly one line on stderr;
#   success (EXIT=0): exit 0 and nothing on stderr (with JSON=ON, stdout is one JSON object).
# CTest's PASS_REGULAR_EXPRESSION ignores the exit code, so this script checks the contract
# and, only when all of it holds, prints one `run_cli ok: stderr=<...>` (failure) or
# `run_cli ok: stdout=<...>` (success) line for the test's PASS_REGULAR_EXPRESSION to match
# the message against. Any broken check ends the script with an error and without that line.
#
#   cmake -DMGRL=path/to/mgrl "-DARGS=inspect|bad.bvh" [-DWORKDIR=dir] [-DEXIT=nonzero|N]
#         [-DJSON=ON] -P run_cli.cmake
#
# ARGS separates the arguments with '|' (a ';' would not survive add_test).

if(NOT MGRL)
  message(FATAL_ERROR "run_cli: pass -DMGRL=path/to/mgrl")
endif()
if("${EXIT}" STREQUAL "")  # not if(NOT EXIT): EXIT=0 is false
  set(EXIT nonzero)
endif()
if(NOT WORKDIR)
  set(WORKDIR .)
endif()
string(REPLACE "|" ";" arguments "${ARGS}")

execute_process(
  COMMAND "${MGRL}" ${arguments}
  WORKING_DIRECTORY "${WORKDIR}"
  RESULT_VARIABLE status
  OUTPUT_VARIABLE out
  ERROR_VARIABLE err)

set(shown "mgrl ${ARGS} (in ${WORKDIR})\n--- exit: ${status}\n--- stdout:\n${out}\n--- stderr:\n${err}\n---")

# A signal (crash, abort) comes back as text such as "Segmentation fault".
if(NOT status MATCHES "^[0-9]+$")
  message(FATAL_ERROR "run_cli: expected an exit code, found a crash: ${shown}")
endif()

if(EXIT STREQUAL "nonzero")
  if(status EQUAL 0)
    message(FATAL_ERROR "run_cli: expected a non-zero exit, found 0: ${shown}")
  endif()
elseif(NOT status EQUAL EXIT)
  message(FATAL_ERROR "run_cli: expected exit ${EXIT}, found ${status}: ${shown}")
endif()

if(status EQUAL 0)
  if(NOT err STREQUAL "")
    message(FATAL_ERROR "run_cli: expected nothing on stderr after success, found some: ${shown}")
  endif()
  if(JSON)
    string(JSON type ERROR_VARIABLE json_error TYPE "${out}")
    if(json_error OR NOT type STREQUAL "OBJECT")
      message(FATAL_ERROR "run_cli: expected one JSON object on stdout, found ${json_error} (${type}): ${shown}")
    endif()
  endif()
  message("run_cli ok: stdout=<${out}>")
else()
  if(NOT out STREQUAL "")
    message(FATAL_ERROR "run_cli: expected nothing on stdout after an error, found some: ${shown}")
  endif()
  if(NOT err MATCHES "^[^\n]+\n$")
    message(FATAL_ERROR "run_cli: expected exactly one line on stderr, found otherwise: ${shown}")
  endif()
  string(REGEX REPLACE "\n$" "" line "${err}")
  message("run_cli ok: stderr=<${line}>")
endif()
