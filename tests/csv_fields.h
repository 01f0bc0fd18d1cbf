// Reading the experiments' CSV rows back in the experiment tests. The project
// never writes quoted fields for the built-in scenes the tests use.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace springlab::csv_fields {

inline std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields(1);
  for (char c : line) {
    if (c == ',') {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

// The number a field holds, failing the test when it holds anything else. An
// empty field (a value the run could not give) is NaN, and a failure unless
// `empty_allowed`.
inline double field_number(const std::string& field, bool empty_allowed = false) {
  if (!empty_allowed) {
    EXPECT_FALSE(field.empty()) << "expected a number, got an empty field";
  }
  if (field.empty()) return std::nan("");
  std::size_t end = 0;
  const double value = std::stod(field, &end);
  EXPECT_EQ(end, field.size()) << "not a number: '" << field << "'";
  return value;
}

}  // namespace springlab::csv_fields
