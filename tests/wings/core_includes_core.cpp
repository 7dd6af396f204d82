// The control of wing_arrows: the same build of a core source that includes
// a core header succeeds, so that the failure there is the backward include.
#include "loopfarm/core/loop.hpp"
