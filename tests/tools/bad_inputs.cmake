# The bad-input corpus in tests/tools/bad-inputs/ (see tests/CMakeLists.txt): one
# CTest test per case directory, bad_input.<case>, run by bad_inputs_test.sh
# against the real binary, so that a failure names its case. A new case
# directory is picked up at the next build (CONFIGURE_DEPENDS).
file(GLOB loopfarm_bad_input_cases LIST_DIRECTORIES true CONFIGURE_DEPENDS
     ${CMAKE_CURRENT_LIST_DIR}/bad-inputs/*)
foreach(case_dir IN LISTS loopfarm_bad_input_cases)
  if(IS_DIRECTORY ${case_dir})
    get_filename_component(case_name ${case_dir} NAME)
    add_test(NAME bad_input.${case_name}
             COMMAND ${CMAKE_CURRENT_LIST_DIR}/bad_inputs_test.sh $<TARGET_FILE:loopfarm_cli>
                     ${CMAKE_CURRENT_LIST_DIR}/bad-inputs ${case_name})
    # The database cases run loopfarm run (MPI singleton, as root in CI) in their setup.
    set_tests_properties(bad_input.${case_name} PROPERTIES
      TIMEOUT 300
      LABELS bad_input
      ENVIRONMENT "OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1")
  endif()
endforeach()
