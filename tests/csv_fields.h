// Reading springlab's CSV output back in the tests. The project never writes
// quoted fields for the built-in scenes the tests use.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "run_process.h"

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

// A CSV of numbers (the energy and trajectory files): its header line and
// rows. Fails the test unless every line ends in '\n', every field parses
// whole as a finite number and every row has as many fields as the header.
struct NumberCsv {
  std::string header;
  std::vector<std::vector<double>> rows;
};

inline NumberCsv read_number_csv(const std::filesystem::path& path) {
  NumberCsv csv;
  const std::string text = springlab::testing::read_text(path);
  EXPECT_FALSE(text.empty()) << path;
  if (text.empty()) return csv;
  EXPECT_EQ(text.back(), '\n') << path << ": last line not terminated";
  std::istringstream lines(text);
  std::getline(lines, csv.header);
  const std::size_t columns = split_fields(csv.header).size();
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<double> row;
    for (const std::string& cell : split_fields(line)) {
      char* end = nullptr;
      const double value = std::strtod(cell.c_str(), &end);
      EXPECT_TRUE(!cell.empty() && end == cell.c_str() + cell.size() && std::isfinite(value))
          << path << ": bad number '" << cell << "' in line '" << line << "'";
      row.push_back(value);
    }
    EXPECT_EQ(row.size(), columns) << path << ": line '" << line << "'";
    csv.rows.push_back(std::move(row));
  }
  return csv;
}

}  // namespace springlab::csv_fields
