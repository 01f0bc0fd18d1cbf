#include "models/core/decimal_text.h"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <system_error>

namespace springlab {

// Where the standard library converts floating point (libstdc++ 11 and
// later: the native build), it does the work. The web build's libc++
// (Emscripten 3.1.6, LLVM 14) has only the integer conversions: there the
// same results come from the C library's correctly rounded printf/strtod.
#if defined(__cpp_lib_to_chars)

std::string shortest_decimal(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

const char* read_decimal(const char* first, const char* last, double& value) {
  const auto result = std::from_chars(first, last, value);
  return result.ec == std::errc() ? result.ptr : nullptr;
}

#else

// The fewest significant digits that read back to `value`; %.*g rounds
// correctly, so of the shortest decimals it gives the nearest, as
// to_chars. (%g picks fixed or scientific notation by the exponent,
// to_chars by the length: either form reads back the same.)
std::string shortest_decimal(double value) {
  char buffer[64];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
    if (std::strtod(buffer, nullptr) == value) break;
  }
  return buffer;
}

const char* read_decimal(const char* first, const char* last, double& value) {
  // from_chars's pattern: strtod's, less leading whitespace, '+' and hex.
  const std::string text(first, last);
  const char* s = text.c_str();
  const char* digits = s + (*s == '-' ? 1 : 0);
  if (text.empty() || *s == '+' || std::strchr(" \t\n\v\f\r", *s) != nullptr ||
      (digits[0] == '0' && (digits[1] == 'x' || digits[1] == 'X'))) {
    return nullptr;
  }
  char* end = nullptr;
  errno = 0;
  const double parsed = std::strtod(s, &end);
  if (end == s || errno == ERANGE) return nullptr;
  value = parsed;
  return first + (end - s);
}

#endif

}  // namespace springlab
