// clogscope.run_experiment's core: a whole manifest run (pipeline::RunManifest, as `clogscope run`
// and `measure --manifest`), its step results as objects. The Python layer reads the diameter
// table the run wrote into a DataFrame.
//
// The steps' and feedstock's statuses are given as the table's words, in one place (StatusText).
#include "pipeline/experiment.h"

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "pipeline/feedstock.h"
#include "pipeline/manifest_run.h"

namespace clogscope::python {
namespace {

// A step's or feedstock's status as the diameter table's status column writes it.
std::string StatusText(const pipeline::StepResult& r) { return model::StepStatusName(r.status); }
std::string StatusText(const pipeline::FeedstockResult& r) {
  return pipeline::FeedstockStatusName(r.status);
}

}  // namespace

void BindExperiment(py::module_& m) {
  py::class_<pipeline::FeedstockResult>(m, "FeedstockResult",
                                        "A step's feedstock filament: diameter, speeds, slip.")
      .def_property_readonly(
          "status", [](const pipeline::FeedstockResult& r) { return StatusText(r); },
          "'ok', 'too_few_pairs' or 'failed'.")
      .def_readonly("detail", &pipeline::FeedstockResult::detail)
      .def_readonly("video", &pipeline::FeedstockResult::video)
      .def_readonly("n_pairs", &pipeline::FeedstockResult::n_pairs)
      .def_readonly("diameter_px", &pipeline::FeedstockResult::diameter_px)
      .def_readonly("diameter_um", &pipeline::FeedstockResult::diameter_um)
      .def_readonly("diameter_ci95_um", &pipeline::FeedstockResult::diameter_ci95_um)
      .def_readonly("speed_mm_s", &pipeline::FeedstockResult::speed_mm_s)
      .def_readonly("speed_ci95_mm_s", &pipeline::FeedstockResult::speed_ci95_mm_s)
      .def_readonly("slip_pct", &pipeline::FeedstockResult::slip_pct)
      .def_readonly("slip_ci95_pct", &pipeline::FeedstockResult::slip_ci95_pct);

  py::class_<pipeline::StepResult>(m, "StepResult",
                                   "One step of an experiment: the diameter table's row.")
      .def_property_readonly("step", [](const pipeline::StepResult& r) { return r.spec.step; })
      .def_property_readonly("temperature_c",
                             [](const pipeline::StepResult& r) { return r.spec.temperature_c; })
      .def_property_readonly(
          "status", [](const pipeline::StepResult& r) { return StatusText(r); },
          "'ok', 'too_few_frames' or 'failed'.")
      .def_readonly("detail", &pipeline::StepResult::detail)
      .def_readonly("n_examined", &pipeline::StepResult::n_examined)
      .def_readonly("n_valid", &pipeline::StepResult::n_valid)
      .def_readonly("n_used", &pipeline::StepResult::n_used)
      .def_readonly("n_rejected", &pipeline::StepResult::n_rejected)
      .def_readonly("mean_px", &pipeline::StepResult::mean_px)
      .def_readonly("std_px", &pipeline::StepResult::std_px)
      .def_readonly("has_um", &pipeline::StepResult::has_um)
      .def_readonly("mean_um", &pipeline::StepResult::mean_um)
      .def_readonly("std_um", &pipeline::StepResult::std_um)
      .def_readonly("sem_um", &pipeline::StepResult::sem_um)
      .def_readonly("cal_sigma_um", &pipeline::StepResult::cal_sigma_um,
                    "The calibration's share of the mean's uncertainty (systematic).")
      .def_readonly("ci95_um", &pipeline::StepResult::ci95_um,
                    "95 % half-width: t·SEM and 1.96·cal_sigma_um in quadrature.")
      .def_readonly("feedstock", &pipeline::StepResult::feedstock)
      .def("__repr__", [](const pipeline::StepResult& r) {
        return fmt::format("StepResult(step={}, status={!r}, n_used={}, mean_um={:.3f} ± {:.3f})",
                           r.spec.step, StatusText(r), r.n_used, r.mean_um, r.ci95_um);
      });

  py::class_<pipeline::ManifestRunReport>(m, "ExperimentReport",
                                          "What run_experiment did: steps, conversion, "
                                          "prediction, files written.")
      .def_readonly("steps", &pipeline::ManifestRunReport::steps, "StepResult per step.")
      .def_readonly("conversion", &pipeline::ManifestRunReport::conversion,
                    "The ScaleCalibration the widths were converted with, or None.")
      .def_readonly("prediction", &pipeline::ManifestRunReport::prediction,
                    "PredictionRun (full pipeline) or None.")
      .def_readonly("files", &pipeline::ManifestRunReport::files)
      .def_readonly("warnings", &pipeline::ManifestRunReport::warnings)
      .def_readonly("cancelled", &pipeline::ManifestRunReport::cancelled);

  m.def(
      "_run_manifest",
      [](const std::string& manifest, const std::string& out_dir, std::optional<int> samples,
         int jobs, bool resume, std::optional<double> scale_um_per_px,
         const std::string& calib_path, bool full_pipeline,
         std::optional<vision::StrandMeasureOptions> options) {
        pipeline::ManifestRunOptions o;
        o.manifest = manifest;
        o.out_dir = out_dir;
        o.samples = samples;
        o.jobs = jobs;
        o.resume = resume;
        o.scale_um_per_px = scale_um_per_px;
        o.calib_path = calib_path;
        o.full_pipeline = full_pipeline;
        if (options) {
          // Only what the options say beyond the defaults overrides the manifest.
          const vision::StrandMeasureOptions defaults;
          o.strand = *options;
          o.roi_given = !options->roi.empty();
          o.polarity_given = options->polarity != defaults.polarity;
          o.target_given = options->target != defaults.target;
          if (options->band_start_px != defaults.band_start_px)
            o.band.start_px = options->band_start_px;
          if (options->band_height_px != defaults.band_height_px)
            o.band.height_px = options->band_height_px;
        }
        std::string why;
        if (!o.Validate(&why)) throw py::value_error(why);
        py::gil_scoped_release release;
        return pipeline::RunManifest(o);
      },
      py::arg("manifest"), py::arg("out_dir"), py::arg("samples"), py::arg("jobs"),
      py::arg("resume"), py::arg("scale_um_per_px"), py::arg("calib_path"),
      py::arg("full_pipeline"), py::arg("options"),
      "pipeline::RunManifest; use clogscope.run_experiment.");
}

}  // namespace clogscope::python
