// Lag inputs: the commanded profile reader (moves and linear forms) and measure's frames table as
// the lag fit reads it. What a reader accepts goes on into the model (the outlet flow, the fit), so
// that the numbers it lets through are fuzzed there too. The first byte picks the reader.
#include <stdexcept>
#include <string>
#include <vector>

#include "fuzz/fuzz_util.h"
#include "model/lag_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace clogscope::model;
  if (size < 1) return 0;
  const int reader = data[0] % 3;
  const std::string path = clogscope::fuzz::AsFile(data + 1, size - 1, ".csv");
  try {
    if (reader < 2) {
      const FlowProfile p =
          ReadFlowProfile(path, reader == 0 ? ProfileForm::kMoves : ProfileForm::kLinear, 1.75);
      const double mid = 0.5 * (p.StartS() + p.EndS());
      const std::vector<double> times = {p.StartS() - 1, p.StartS(), mid, p.EndS(), p.EndS() + 1};
      OutletFlow(p, 0.1, 0.05, times);
    } else {
      const WidthSeries w = ReadWidthSeries(path);
      if (w.samples.size() >= 8 && w.samples.size() <= 400) {
        const FlowProfile steps = ProfileFromMoves({0, 1, 2.5, 4, 5.5}, {3, 9, 4, 12, 3});
        LagFitOptions o;
        o.max_iterations = 20;
        FitLag(steps, w.samples, o);
      }
    }
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
