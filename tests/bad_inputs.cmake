# The bad-input corpus tests/bad-inputs/ (see tests/CMakeLists.txt).
