// Force-included into the fuzzers (fuzz/CMakeLists.txt) before toml++.
//
// The loopfarm binary links Debian's libtomlplusplus, built with GCC and
// NDEBUG, where toml++'s internal assertions (TOML_ASSERT, TOML_ASSERT_ASSUME)
// compile to nothing. The fuzzers compile toml++ header-only, so without this
// they would abort on assertions the shipped parser does not have (e.g.
// parse_value's on "a = [2, }") and stop there instead of exploring further.
// What follows a violated precondition is still checked: memory errors by
// ASan, and undefined behaviour such as TOML_UNREACHABLE by UBSan.
#pragma once
#define TOML_ASSERT(expr) static_assert(true)
