// Must not compile: a core source that includes a header of the search wing.
// The wings' arrows point one way (CMakeLists.txt): the test wing_arrows
// builds this against the core's include tree and expects the build to fail.
#include "loopfarm/search/job.hpp"
