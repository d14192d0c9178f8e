#include "common/csv.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace clogscope {

std::string CsvEscape(const std::string& field) {
  if (field.find_first_of(",\"\n\r") == std::string::npos) return field;
  std::string out = "\"";
  for (char c : field) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

std::string CsvLine(const std::vector<std::string>& fields) {
  std::string line;
  for (size_t i = 0; i < fields.size(); ++i) {
    if (i) line += ',';
    line += CsvEscape(fields[i]);
  }
  return line;
}

std::string CsvNumber(std::optional<double> value, int decimals) {
  if (!value || !std::isfinite(*value)) return "";
  return fmt::format("{:.{}f}", *value, decimals);
}

double ParseNumberField(const std::string& text, const std::string& where,
                        const std::string& what) {
  if (text.empty()) throw std::invalid_argument(fmt::format("{}: {} is missing", where, what));
  size_t used = 0;
  double v = NAN;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v)) {
    throw std::invalid_argument(fmt::format("{}: {} '{}' is not a number", where, what, text));
  }
  return v;
}

int CsvTable::Column(const std::string& name) const {
  for (size_t i = 0; i < header.size(); ++i) {
    if (header[i] == name) return static_cast<int>(i);
  }
  return -1;
}

CsvTable ParseCsv(const std::string& text, const std::string& source_name) {
  CsvTable table;
  std::vector<std::string> fields;
  std::string field;
  bool in_quotes = false;
  bool have_header = false;
  int line = 1;
  int record_line = 1;
  size_t i = 0;
  auto finish_record = [&]() {
    fields.push_back(field);
    field.clear();
    bool blank = fields.size() == 1 && fields[0].empty();
    bool comment = !fields.empty() && !fields[0].empty() && fields[0][0] == '#';
    if (!blank && !comment) {
      for (auto& f : fields) {
        // Trim surrounding blanks (and a stray CR from Windows files).
        size_t b = f.find_first_not_of(" \t\r");
        size_t e = f.find_last_not_of(" \t\r");
        f = b == std::string::npos ? "" : f.substr(b, e - b + 1);
      }
      if (!have_header) {
        table.header = fields;
        have_header = true;
      } else {
        if (fields.size() != table.header.size()) {
          throw std::invalid_argument(
              fmt::format("{}:{}: expected {} fields as in the header, found {}", source_name,
                          record_line, table.header.size(), fields.size()));
        }
        table.rows.push_back(fields);
        table.row_line_numbers.push_back(record_line);
      }
    }
    fields.clear();
  };
  for (; i < text.size(); ++i) {
    char c = text[i];
    if (in_quotes) {
      if (c == '"') {
        if (i + 1 < text.size() && text[i + 1] == '"') {
          field += '"';
          ++i;
        } else {
          in_quotes = false;
        }
      } else {
        if (c == '\n') ++line;
        field += c;
      }
    } else if (c == '"') {
      in_quotes = true;
    } else if (c == ',') {
      fields.push_back(field);
      field.clear();
    } else if (c == '\n') {
      finish_record();
      ++line;
      record_line = line;
    } else {
      field += c;
    }
  }
  if (in_quotes) {
    throw std::invalid_argument(
        fmt::format("{}:{}: unterminated quoted field", source_name, record_line));
  }
  if (!field.empty() || !fields.empty()) finish_record();
  if (!have_header) throw std::invalid_argument(source_name + ": no header line");
  return table;
}

}  // namespace clogscope
