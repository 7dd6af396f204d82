// find_toml_hazard (job.hpp): a small lexer that knows just enough TOML
// (comments, the four kinds of string, table headers, arrays and inline
// tables) to find the two constructs toml++ 3.3 mishandles.
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>

#include "loopfarm/search/job.hpp"

namespace loopfarm {

namespace {

bool is_bare_key_char(unsigned char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

// "U+02DE" for a valid UTF-8 sequence at `at`, else "byte 0xCB".
std::string describe_non_ascii(std::string_view text, size_t at) {
  const auto byte = [&](size_t i) { return i < text.size() ? static_cast<unsigned char>(text[i]) : 0u; };
  const unsigned lead = byte(at);
  int length = 0;
  unsigned code = 0;
  if ((lead & 0xE0) == 0xC0) {
    length = 2;
    code = lead & 0x1F;
  } else if ((lead & 0xF0) == 0xE0) {
    length = 3;
    code = lead & 0x0F;
  } else if ((lead & 0xF8) == 0xF0) {
    length = 4;
    code = lead & 0x07;
  }
  bool valid = length > 0;
  for (int k = 1; valid && k < length; ++k) {
    const unsigned next = byte(at + static_cast<size_t>(k));
    valid = (next & 0xC0) == 0x80;
    code = (code << 6) | (next & 0x3F);
  }
  char buffer[32];
  if (valid) {
    std::snprintf(buffer, sizeof buffer, "U+%04X", code);
  } else {
    std::snprintf(buffer, sizeof buffer, "byte 0x%02X", lead);
  }
  return buffer;
}

}  // namespace

std::optional<TomlHazard> find_toml_hazard(std::string_view text) {
  size_t i = 0;
  int line = 1;
  size_t line_start = 0;
  const auto at = [&](size_t k) -> unsigned char { return k < text.size() ? static_cast<unsigned char>(text[k]) : 0; };
  const auto hazard = [&](size_t k, std::string message) {
    return TomlHazard{line, static_cast<int>(k - line_start) + 1, std::move(message)};
  };
  const auto newline = [&](size_t k) {  // `k` is the '\n'
    ++line;
    line_start = k + 1;
  };
  // A UTF-8 byte order mark is allowed at the very start.
  if (text.substr(0, 3) == "\xEF\xBB\xBF") i = 3;
  std::string open;             // the [ of arrays and { of inline tables now open, innermost last
  bool statement_start = true;  // at the start of a line outside any value
  bool in_header = false;       // inside [table] or [[array.of.tables]]
  unsigned char prev = '\n';    // the last character outside strings, blanks and comments
  while (i < text.size()) {
    const unsigned char c = at(i);
    if (c == '\n') {
      newline(i);
      ++i;
      // Inside an array a newline is only a blank: "[1,\n0a='x'" still has a
      // value after the comma, which toml++ scans as such.
      if (open.empty()) prev = '\n';
      in_header = false;
      statement_start = open.empty();
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') {
      ++i;
      continue;
    }
    if (c == '#') {  // a comment: anything up to the end of the line
      while (i < text.size() && at(i) != '\n') ++i;
      continue;
    }
    if (c >= 0x80) {
      return hazard(i, "non-ASCII character " + describe_non_ascii(text, i) +
                           " outside a string or comment (TOML allows it only inside quotes or after #)");
    }
    if (statement_start && c == '[') {
      // A table header: the name must begin with a bare-key character or a quote.
      statement_start = false;
      in_header = true;
      size_t k = i + 1;
      if (at(k) == '[') ++k;
      while (at(k) == ' ' || at(k) == '\t') ++k;
      const unsigned char first = at(k);
      // At the end of the text toml++ reports the error itself; "[ [" too.
      if (k < text.size() && first != ']' && first != '[' && !is_bare_key_char(first) && first != '"' &&
          first != '\'') {
        std::string what;
        if (first >= 0x80) {
          what = "non-ASCII character " + describe_non_ascii(text, k);
        } else if (first < 0x20 || first == 0x7F) {
          char buffer[16];  // a control character or newline: named, so the message stays one line
          std::snprintf(buffer, sizeof buffer, "byte 0x%02X", first);
          what = buffer;
        } else {
          what = std::string("'") + static_cast<char>(first) + "'";
        }
        return hazard(k, "a table header must begin with a name, not " + what);
      }
      if (first == '[' && at(i + 1) == '[') {
        return hazard(k, "a table header must begin with a name, not '['");
      }
      i = k;
      prev = '[';
      continue;
    }
    statement_start = false;
    // A value that starts with neither a quote, [ nor {: toml++ scans it up
    // to the next blank, ], }, ',' or # (quotes and brackets inside belong to
    // it: "0xfl['x"), testing every character for whitespace.
    const bool value_may_begin = prev == '=' || ((prev == '[' || prev == ',') && !open.empty() && open.back() == '[');
    if (value_may_begin && !in_header && c != '"' && c != '\'' && c != '[' && c != '{' && c != ']' && c != '}' &&
        c != ',') {
      size_t k = i;
      while (k < text.size() && at(k) != ' ' && at(k) != '\t' && at(k) != '\n' && at(k) != '\r' && at(k) != '\v' &&
             at(k) != '\f' && at(k) != ']' && at(k) != '}' && at(k) != ',' && at(k) != '#') {
        if (at(k) >= 0x80) {
          return hazard(k, "non-ASCII character " + describe_non_ascii(text, k) +
                               " outside a string or comment (TOML allows it only inside quotes or after #)");
        }
        ++k;
      }
      if (k > i) {  // else c is a terminator itself (\v, \f): taken below like any other character
        prev = at(k - 1);
        i = k;
        continue;
      }
    }
    // A quote opens a string only where TOML lets one begin: a key or a
    // value. Elsewhere ("0'x'") toml++ reads it as part of a bare value and
    // tests the characters after it, so this lexer must not skip them either.
    const bool string_may_begin =
        prev == '\n' || prev == '=' || prev == '[' || prev == ',' || prev == '{' || prev == '.';
    if ((c == '"' || c == '\'') && string_may_begin) {
      const bool multi = at(i + 1) == c && at(i + 2) == c;
      if (multi) {
        i += 3;
        while (i < text.size() && !(at(i) == c && at(i + 1) == c && at(i + 2) == c)) {
          if (at(i) == '\n') newline(i);
          if (c == '"' && at(i) == '\\') {
            // toml++ tests what follows a backslash here for whitespace: the
            // escaped character itself, the blanks after it, and after a
            // line-ending backslash the first character of the next text.
            const auto refuse = [&](size_t where, const char* context) {
              return hazard(where, "non-ASCII character " + describe_non_ascii(text, where) + " " + context +
                                       " in a multi-line string (toml++ 3.3 cannot read it; escape it as \\uXXXX)");
            };
            size_t k = i + 1;
            if (at(k) >= 0x80) return refuse(k, "right after a backslash");
            bool blank = false;
            while (at(k) == ' ' || at(k) == '\t') {
              ++k;
              blank = true;
            }
            if (blank && at(k) >= 0x80) return refuse(k, "after a backslash and blanks");
            if (at(k) == '\n' || (at(k) == '\r' && at(k + 1) == '\n')) {
              while (k < text.size() && (at(k) == ' ' || at(k) == '\t' || at(k) == '\r' || at(k) == '\n')) {
                if (at(k) == '\n') newline(k);
                ++k;
              }
              if (at(k) >= 0x80) return refuse(k, "right after a line-ending backslash");
              i = k;
              continue;
            }
            i += 2;  // an escape: skip the escaped character (a quote, say)
            continue;
          }
          ++i;
        }
        i += 3;
        prev = c;
        continue;
      }
      ++i;
      while (i < text.size() && at(i) != c && at(i) != '\n') {
        i += c == '"' && at(i) == '\\' && at(i + 1) != '\n' ? 2 : 1;
      }
      if (at(i) == c) ++i;
      prev = c;
      continue;
    }
    prev = c;
    if (!in_header) {
      if (c == '[' || c == '{') open += static_cast<char>(c);
      if ((c == ']' || c == '}') && !open.empty()) open.pop_back();
    }
    ++i;
  }
  return std::nullopt;
}

}  // namespace loopfarm
