// Tables (diameter tables, pins, fits, temperature logs): the CSV reader and the number parser.
#include <stdexcept>
#include <string>

#include "common/csv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const clogscope::CsvTable t = clogscope::ParseCsv(text, "fuzz.csv");
    for (const auto& row : t.rows) {
      for (const auto& cell : row) {
        try {
          clogscope::ParseNumberField(cell, "fuzz.csv", "cell");
        } catch (const std::invalid_argument&) {
        }
      }
    }
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
