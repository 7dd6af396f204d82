# Fault and concurrent-reading tests (see tests/CMakeLists.txt): the farm
# killed (SIGKILL) and stopped (SIGTERM) at random moments and resumed,
# damaged database files refused untouched, a disk that fills, and reading
# while a run writes.
# tests/tools/fault_test.sh describes each case. Each runs 2-rank jobs of about
# 15 s (a few times over for kill and term) on the 2 cores CI has.
# Their time limit, LOOPFARM_FAULT_TEST_TIMEOUT, is the farm tests' (set in
# tests/CMakeLists.txt; scripts/test.sh --sanitize gives 900 s: instrumented,
# fault_kill needed more than 240 s even with 150 starts).
foreach(fault_case kill term damage full concurrent)
  add_test(NAME fault_${fault_case}
           COMMAND ${CMAKE_CURRENT_LIST_DIR}/fault_test.sh $<TARGET_FILE:loopfarm_cli> ${fault_case}
                   ${MPIEXEC_EXECUTABLE})
  set_tests_properties(fault_${fault_case} PROPERTIES
    PROCESSORS 2
    TIMEOUT ${LOOPFARM_FAULT_TEST_TIMEOUT}
    ENVIRONMENT "OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1")
endforeach()
