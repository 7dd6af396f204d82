# CI's sanitized subset (scripts/test.sh builds it with clang, AddressSanitizer
# and UndefinedBehaviorSanitizer into build/sanitize-subset and runs it after
# the normal suite). scripts/test.sh --sanitize runs everything instrumented,
# but its build alone takes some 15 minutes on 2 cores, most of it the
# numerical core (src/core/cycle.cpp and the search) compiled with the sanitizers;
# CI cannot afford that. These test programs need only a few library sources,
# which each compiles itself (as fuzz/ does), so the whole subset builds and
# runs in a few minutes:
#
#   loop_test               the loop's geometry and frames (loop.cpp, sample_loops.cpp)
#   equilibrium_test        the equilibrium solve and assembly (equilibrium.cpp, assembly.cpp)
#   sampler_test            the job's parameter space and sampler (job.cpp, job_space.cpp, toml_hazard.cpp,
#                           parameter_space.cpp, sampler.cpp, and families.cpp for the family names)
#   results_database_test   the results database, SQLite's C API (results_database.cpp, results_queries.cpp,
#                           results_schema.cpp, sqlite_support.cpp, candidate_index.cpp, results_rekey.cpp
#                           with the canonical form it calls: canonical.cpp, representation.cpp)
#   cycle_start_test        the rigid motion's tracer and the cycle started on it
#                           (closure_solver.cpp, circuit_trace.cpp, motion.cpp, motion_start.cpp, cycle.cpp,
#                           cycle_derivatives.cpp, cycle_start.cpp, constructions.cpp)
#
# The parsers are sanitized by the fuzzers (fuzz/), the rest only by
# scripts/test.sh --sanitize. A link error here means a test needs a source more:
# add it to the list.
find_package(GTest REQUIRED)
include(GoogleTest)
enable_testing()

add_custom_target(sanitized_subset)
function(loopfarm_add_sanitized_test path)
  get_filename_component(name ${path} NAME)
  add_executable(${name} ${PROJECT_SOURCE_DIR}/tests/${path}.cpp ${ARGN})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/include ${PROJECT_SOURCE_DIR}/src
                                             ${PROJECT_SOURCE_DIR}/tests/support)
  target_compile_definitions(${name} PRIVATE LOOPFARM_VERSION="${PROJECT_VERSION}")
  target_link_libraries(${name} PRIVATE loopfarm_options Eigen3::Eigen GTest::gtest_main)
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60)
  add_dependencies(sanitized_subset ${name})
endfunction()

set(loopfarm_geometry ${PROJECT_SOURCE_DIR}/src/core/loop.cpp ${PROJECT_SOURCE_DIR}/src/core/sample_loops.cpp)
loopfarm_add_sanitized_test(core/loop_test ${loopfarm_geometry})
loopfarm_add_sanitized_test(core/equilibrium_test ${loopfarm_geometry}
  ${PROJECT_SOURCE_DIR}/src/core/equilibrium.cpp ${PROJECT_SOURCE_DIR}/src/core/assembly.cpp)
loopfarm_add_sanitized_test(search/sampler_test
  ${PROJECT_SOURCE_DIR}/src/search/job.cpp ${PROJECT_SOURCE_DIR}/src/search/job_space.cpp
  ${PROJECT_SOURCE_DIR}/src/search/toml_hazard.cpp ${PROJECT_SOURCE_DIR}/src/search/parameter_space.cpp
  ${PROJECT_SOURCE_DIR}/src/search/sampler.cpp ${PROJECT_SOURCE_DIR}/src/search/nlopt_algorithms.cpp
  ${PROJECT_SOURCE_DIR}/src/search/families.cpp ${PROJECT_SOURCE_DIR}/src/core/loop.cpp)
target_link_libraries(sampler_test PRIVATE tomlplusplus::tomlplusplus NLopt::nlopt)
loopfarm_add_sanitized_test(farm/results_database_test ${PROJECT_SOURCE_DIR}/src/farm/results_database.cpp
  ${PROJECT_SOURCE_DIR}/src/farm/results_queries.cpp ${PROJECT_SOURCE_DIR}/src/farm/results_schema.cpp
  ${PROJECT_SOURCE_DIR}/src/farm/sqlite_support.cpp ${PROJECT_SOURCE_DIR}/src/farm/candidate_index.cpp
  ${PROJECT_SOURCE_DIR}/src/farm/results_rekey.cpp ${PROJECT_SOURCE_DIR}/src/search/canonical.cpp
  ${PROJECT_SOURCE_DIR}/src/search/representation.cpp ${PROJECT_SOURCE_DIR}/src/core/loop.cpp)
target_link_libraries(results_database_test PRIVATE SQLite::SQLite3)
loopfarm_add_sanitized_test(core/cycle_start_test ${loopfarm_geometry}
  ${PROJECT_SOURCE_DIR}/src/core/equilibrium.cpp ${PROJECT_SOURCE_DIR}/src/core/assembly.cpp
  ${PROJECT_SOURCE_DIR}/src/core/closure_solver.cpp ${PROJECT_SOURCE_DIR}/src/core/circuit_trace.cpp
  ${PROJECT_SOURCE_DIR}/src/core/motion.cpp ${PROJECT_SOURCE_DIR}/src/core/motion_start.cpp
  ${PROJECT_SOURCE_DIR}/src/core/cycle.cpp ${PROJECT_SOURCE_DIR}/src/core/cycle_derivatives.cpp
  ${PROJECT_SOURCE_DIR}/src/core/cycle_start.cpp ${PROJECT_SOURCE_DIR}/src/core/constructions.cpp)
