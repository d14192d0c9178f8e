#pragma once

#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace clogscope {

// Quotes a CSV field when it holds a comma, quote or newline (RFC 4180).
std::string CsvEscape(const std::string& field);

// Joins fields into one CSV line (no newline).
std::string CsvLine(const std::vector<std::string>& fields);

// Formats a number for a table: fixed `decimals`, or an empty field for a missing value.
std::string CsvNumber(std::optional<double> value, int decimals);

// A parsed CSV table. Lines starting with '#' are provenance comments and are skipped; the first
// remaining line is the header.
struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<int> row_line_numbers;  // 1-based line of each row in the file, for error messages
  // Column index of `name`, or -1.
  int Column(const std::string& name) const;
};

// A number from a table cell or option value. Throws std::invalid_argument "WHERE: WHAT is missing"
// for an empty cell, "WHERE: WHAT 'TEXT' is not a number" for anything but a finite number.
double ParseNumberField(const std::string& text, const std::string& where, const std::string& what);

// Parses CSV text; throws std::invalid_argument naming `source_name` and the line on a malformed
// row.
CsvTable ParseCsv(const std::string& text, const std::string& source_name);

}  // namespace clogscope
