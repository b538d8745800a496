# Script mode (tests/CMakeLists.txt runs it after a test binary is built):
# one ctest test per GoogleTest suite, where gtest_discover_tests makes one
# per test. For binaries whose process start is dear (those that load
# OpenCV's image codecs and with them GDAL's libraries): their short tests
# then share one start per suite.
#
#   cmake -D EXE=<test binary> -D FILTER=<gtest filter or empty>
#         -D OUT=<ctest file to write> -D LABELS=<tier>,<folder>
#         -D ENV_MOD=<ENVIRONMENT_MODIFICATION value> -D ENV=<ENVIRONMENT value or empty>
#         -P gtest_suites.cmake
#
# Each suite's test runs exactly the tests the binary lists for it under
# FILTER (its --gtest_filter names them one by one), so a pattern that
# leaves out part of a suite (a SLOW test run on its own) is honoured.
set(args --gtest_list_tests)
if(FILTER)
  list(APPEND args "--gtest_filter=${FILTER}")
endif()
execute_process(COMMAND ${EXE} ${args} OUTPUT_VARIABLE listing ERROR_VARIABLE err
                RESULT_VARIABLE rc TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${EXE} --gtest_list_tests failed (${rc}): ${err}")
endif()
string(REPLACE "," ";" labels "${LABELS}")
set(props "TIMEOUT 600 LABELS [==[${labels}]==] ENVIRONMENT_MODIFICATION [==[${ENV_MOD}]==]")
if(ENV)
  string(APPEND props " ENVIRONMENT [==[${ENV}]==]")
endif()
set(content "")
set(suite "")
set(tests "")
macro(flush_suite)
  if(suite AND tests)
    list(JOIN tests ":" filter)
    string(APPEND content "add_test([==[${suite}.*]==] [==[${EXE}]==] [==[--gtest_filter=${filter}]==])\n"
                          "set_tests_properties([==[${suite}.*]==] PROPERTIES ${props})\n")
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
