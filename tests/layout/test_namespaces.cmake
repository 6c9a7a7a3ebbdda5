# The test suite compiles in unity batches (CMakeLists.txt, cmake/MgrlUnity.cmake): several
# test files in one translation unit, so two files' helpers of the same name (a Sandbox, a
# kBoxing) would clash, and which files share a batch changes whenever a file is added. So
# each tests/<name>_test.cpp keeps everything it defines in a namespace named after it,
# `namespace <name>_test {` or `namespace mgrl::<name>_test {`, opened before its first
# helper or test case and closed on its last line. Run as
#   cmake -DROOT=<tree> -P test_namespaces.cmake
# it prints each file that breaks the rule and fails. tests/layout/bad_tree/tests/ holds one
# that does (ctest entry layout_test_namespaces_catches).
cmake_minimum_required(VERSION 3.22)
if(NOT DEFINED ROOT)
  message(FATAL_ERROR "test_namespaces.cmake: expected -DROOT=<source tree>, found none")
endif()
get_filename_component(ROOT "${ROOT}" ABSOLUTE)
file(GLOB files "${ROOT}/tests/*_test.cpp")
set(bad 0)
foreach(file IN LISTS files)
  get_filename_component(stem "${file}" NAME_WE)
  file(RELATIVE_PATH shown "${ROOT}" "${file}")
  # Read whole, never as a list of lines: a line with an unmatched '[' or a ';' would merge
  # list elements.
  file(READ "${file}" text)
  set(opening "")
  foreach(candidate "\nnamespace ${stem} {" "\nnamespace mgrl::${stem} {")
    string(FIND "${text}" "${candidate}" at)
    if(at GREATER -1 AND opening STREQUAL "")
      set(opening "${candidate}")
      string(SUBSTRING "${text}" 0 ${at} before)
    endif()
  endforeach()
  string(STRIP "${text}" stripped)
  string(REGEX MATCH "[^\n]*$" last "${stripped}")
  if(opening STREQUAL "")
    message("${shown}: expected its definitions in `namespace ${stem} {` (or `namespace mgrl::${stem} {`), found no such line")
    math(EXPR bad "${bad} + 1")
  elseif(before MATCHES "\n(namespace {|TEST_CASE|TEMPLATE_TEST_CASE|struct |class |const |constexpr |static )")
    message("${shown}: expected `namespace ${stem} {` before the first helper or test case, found `${CMAKE_MATCH_1}` before it")
    math(EXPR bad "${bad} + 1")
  elseif(NOT last MATCHES "^}  // namespace (mgrl::)?${stem}$")
    message("${shown}: expected its last line to close `namespace ${stem}` (`}  // namespace ${stem}`), found `${last}`")
    math(EXPR bad "${bad} + 1")
  endif()
endforeach()
list(LENGTH files count)
if(bad GREATER 0)
  message(FATAL_ERROR "test_namespaces: ${bad} of ${count} test files keep definitions outside their own namespace")
endif()
message("test_namespaces: all ${count} test files keep their definitions in their own namespace")
