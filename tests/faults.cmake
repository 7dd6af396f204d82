# Fault and concurrent-reading tests (see tests/CMakeLists.txt).
