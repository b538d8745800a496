# Script mode (tests/CMakeLists.txt runs it after a test binary is built):
# one ctest test per GoogleTest suite, where gtest_discover_tests makes one
# per test. For binaries whose process start is dear (those that load
# OpenCV's image codecs and with them GDAL's libraries): their short tests
# then share one start per suite.
#
#   cmake -D EXE=<test binary> -D FILTER=<gtest filter or empty>
#         -D OUT=<ctest file to write> -P gtest_suites.cmake
#
# Each suite's test runs exactly the tests the binary lists for it under
# FILTER (its --gtest_filter names them one by one), so a pattern that
# leaves out part of a suite (a SLOW test run on its own) is honoured. OUT
# adds the tests and lists their names in `suite_tests`; the folder's
# include (tests/CMakeLists.txt) gives them their labels and environment.
set(args --gtest_list_tests)
if(FILTER)
  list(APPEND args "--gtest_filter=${FILTER}")
endif()
execute_process(COMMAND ${EXE} ${args} OUTPUT_VARIABLE listing ERROR_VARIABLE err
                RESULT_VARIABLE rc TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${EXE} --gtest_list_tests failed (${rc}): ${err}")
endif()
set(content "set(suite_tests \"\")\n")
set(suite "")
set(tests "")
macro(flush_suite)
  if(suite AND tests)
    list(JOIN tests ":" filter)
    string(APPEND content "add_test([==[${suite}.*]==] [==[${EXE}]==] [==[--gtest_filter=${filter}]==])\n"
                          "list(APPEND suite_tests [==[${suite}.*]==])\n")
  endif()
  set(tests "")
endmacro()
string(REPLACE "\n" ";" lines "${listing}")
foreach(line IN LISTS lines)
  if(line MATCHES "^([^ ][^ ]*)\\.( +#.*)?$")
    flush_suite()
    set(suite "${CMAKE_MATCH_1}")
  elseif(suite AND line MATCHES "^  ([^ ]+)( +#.*)?$")
    list(APPEND tests "${suite}.${CMAKE_MATCH_1}")
  endif()
endforeach()
flush_suite()
file(WRITE "${OUT}" "${content}")
