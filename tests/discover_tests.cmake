# Writes the ctest tests of one Catch2 binary (run after each build of it):
#  - each test case tagged [slow] as a test of its own, named as in Catch, so
#    ctest spreads the long ones over the cores (ctest_costs.cmake orders them);
#  - the other cases of each source file as one test, "FILE: its quick cases",
#    run as `BINARY -# "[#FILE]~[slow]~[.]"`: one process instead of one per case.
#    Every start of a binary that links LibTorch costs about a second of CPU
#    (its operator registry and ~300 libraries: NOTES.md), which was a third
#    of the suite when each of ~430 cases had a process of its own.
# Inputs: TEST_EXECUTABLE, TEST_WORKING_DIR, CTEST_FILE.
if(NOT EXISTS "${TEST_EXECUTABLE}")
  message(FATAL_ERROR "test binary '${TEST_EXECUTABLE}' does not exist")
endif()

set(script "")
function(add_line text)
  set(script "${script}${text}\n" PARENT_SCOPE)
endfunction()

# The [slow] cases, one per line (Catch prints names unwrapped here).
execute_process(
  COMMAND "${TEST_EXECUTABLE}" "[slow]" --list-test-names-only
  OUTPUT_VARIABLE slow_names
  RESULT_VARIABLE rc
  WORKING_DIRECTORY "${TEST_WORKING_DIR}")
if(rc LESS 0)
  message(FATAL_ERROR "listing the tests of '${TEST_EXECUTABLE}' failed: ${slow_names}")
endif()
string(REPLACE "\n" ";" slow_names "${slow_names}")
foreach(name IN LISTS slow_names)
  if(name STREQUAL "")
    continue()
  endif()
  # A test spec treats ',', '[' and ']' specially: escape them.
  set(spec "${name}")
  foreach(char , [ ])
    string(REPLACE "${char}" "\\${char}" spec "${spec}")
  endforeach()
  add_line("add_test([==[${name}]==] \"${TEST_EXECUTABLE}\" [==[${spec}]==])")
  add_line("set_tests_properties([==[${name}]==] PROPERTIES WORKING_DIRECTORY \"${TEST_WORKING_DIR}\")")
endforeach()

# The source files that hold cases not tagged [slow]: Catch lists the
# file-name tags (-#) of the matching cases with their counts. Hidden cases
# ([.], e.g. ekf_test.cpp's tuning records) are excluded by name: a tag
# filter alone would select them.
execute_process(
  COMMAND "${TEST_EXECUTABLE}" "-#" "~[slow]" --list-tags
  OUTPUT_VARIABLE tags
  RESULT_VARIABLE rc
  WORKING_DIRECTORY "${TEST_WORKING_DIR}")
if(rc LESS 0)
  message(FATAL_ERROR "listing the tags of '${TEST_EXECUTABLE}' failed: ${tags}")
endif()
string(REGEX MATCHALL "\\[#[A-Za-z0-9_]+\\]" files "${tags}")
foreach(tag IN LISTS files)
  string(REGEX REPLACE "^\\[#(.*)\\]$" "\\1" file "${tag}")
  set(name "${file}.cpp: its quick cases")
  add_line("add_test([==[${name}]==] \"${TEST_EXECUTABLE}\" \"-#\" [==[${tag}~[slow]~[.]]==])")
  add_line("set_tests_properties([==[${name}]==] PROPERTIES WORKING_DIRECTORY \"${TEST_WORKING_DIR}\")")
endforeach()

file(WRITE "${CTEST_FILE}" "${script}")
