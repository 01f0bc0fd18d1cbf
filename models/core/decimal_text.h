// Doubles as decimal text and back, as std::to_chars and std::from_chars do
// it: the shortest decimal that reads back to the same double ("0.1", not
// "0.10000000000000001"; "2.5e-07"), and a reader of the whole number
// format without leading whitespace, '+' or hexadecimal.
#pragma once

#include <string>

namespace springlab {

// std::to_chars(first, last, value)'s text.
std::string shortest_decimal(double value);
// std::from_chars(first, last, value): where the number ends, or nullptr
// (value untouched) when [first, last) does not start with one. Out of
// range ("1e999") also gives nullptr.
const char* read_decimal(const char* first, const char* last, double& value);

}  // namespace springlab
