// What the store's tests share: the message of a database refused.
#pragma once

#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "loopfarm/farm/results_database.hpp"

namespace loopfarm::testing {

// The message `action` throws as a DatabaseError, which must be a refusal
// (Cause::refused), or "" when it throws none.
inline std::string refusal(const std::function<void()>& action) {
  try {
    action();
  } catch (const DatabaseError& error) {
    EXPECT_EQ(error.cause(), DatabaseError::Cause::refused) << error.what();
    return error.what();
  }
  return "";
}

}  // namespace loopfarm::testing
