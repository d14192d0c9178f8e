#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "apps/band.h"
#include "calib/pixel_scale.h"
#include "model/fit.h"
#include "model/lag_io.h"
#include "model/parameters.h"
#include "model/predictor.h"
#include "model/roller_drive.h"
#include "model/thermal.h"
#include "pipeline/experiment.h"
#include "synthetic/synthetic.h"
#include "vision/motion/feed_speed.h"
#include "vision/motion/gear_speed.h"
#include "vision/scene/scene.h"
#include "vision/scene/strand_measure.h"
#include "watch/live_watch.h"

namespace clogscope::apps {

// Each RunX parses argv (argv[0] is the subcommand name) into an options struct and calls the typed
// function below it; it returns the process exit code. Contract violations surface as
// std::invalid_argument, which main() reports as one line.
int RunRender(int argc, char** argv);
int RunMeasure(int argc, char** argv);
int RunPredict(int argc, char** argv);
int RunCalibrate(int argc, char** argv);
int RunRun(int argc, char** argv);
int RunInspect(int argc, char** argv);
int RunThermal(int argc, char** argv);
int RunDrive(int argc, char** argv);
int RunLag(int argc, char** argv);
int RunWatch(int argc, char** argv);

// --- render --------------------------------------------------------------------------------
struct RenderCommandOptions {
  vision::SceneParams scene;
  int frames = 1;
  double fps = 25.0;
  std::string out;         // directory of PNGs, or a .avi / .mp4 video
  std::string truth_path;  // empty: next to the output (DIR/truth.json or NAME.truth.json)
  // A strand whose width follows the first-order lag of a commanded flow profile: width =
  // lag_um_per_mm3_s · Q_out(frame time). Empty: no lag.
  std::string lag_commanded;
  model::ProfileForm lag_profile_form = model::ProfileForm::kMoves;
  double lag_k_s = 0.1;
  double lag_um_per_mm3_s = 40;
  double filament_diameter_mm = 1.75;
  // A clog sequence for `watch`: the strand narrows by drop_pct % at drop_at_s (0: no drop).
  double drop_pct = 0;
  double drop_at_s = 0;
  bool Validate(std::string* why) const;
};
// Renders and writes frames and truth; returns the truth path written.
std::string RenderToFiles(const RenderCommandOptions& options);

// --- measure -------------------------------------------------------------------------------
struct MeasureCommandOptions {
  std::vector<std::string> inputs;                     // images, directories of images, videos
  std::optional<double> scale_um_per_px;               // converts widths to µm when given
  std::optional<calib::ScaleCalibration> calibration;  // or a calibration (--calib): scale and bias
  BandRequest band;                     // in µm (needs a scale) or px; default: DefaultBand
  vision::StrandMeasureOptions strand;  // band fields are filled from the above
  std::string out_frames;               // per-frame CSV; empty or "-": standard output
  std::string overlay_dir;              // empty: no overlays
  int overlay_every = 0;                // 0: every image, every 25th video frame
  bool flag_outliers = true;
  bool feed_speed = false;  // filament target: feed speed between consecutive video frames
  vision::FeedSpeedOptions feed;
  std::optional<cv::Rect> gear_roi;           // with feed_speed: the drive gear's surface speed
  std::optional<cv::Point2d> gear_centre_px;  // default: the ROI's centre
  std::optional<double> gear_radius_mm;       // required with gear_roi
  bool Validate(std::string* why) const;
  // The band in px from the µm or px options (throws std::invalid_argument on a conflict).
  void ResolveBand();
  // Widths to µm: the calibration's (w − b)·s with its σ, or a plain scale, or none.
  std::optional<calib::ScaleCalibration> Conversion() const;
};

struct MeasureSummary {
  int inputs_ok = 0;
  int inputs_failed = 0;
  int frames = 0;
  int valid_frames = 0;
  int overlays_written = 0;
  int overlay_frames_held_peak = 0;  // most frames kept at once for overlays still to be drawn
  double seconds = 0;
  std::vector<std::string> errors;  // one line per input that could not be read
};

// Measures every frame of every input and writes the per-frame CSV (atomically) and overlays.
// An input that cannot be opened is reported in the summary and skipped.
MeasureSummary MeasureInputs(MeasureCommandOptions options);

// The per-frame CSV's columns, in order (without the feed-speed columns).
const std::vector<std::string>& FrameCsvColumns();
// What --speed appends to them, and --gear-roi after those.
const std::vector<std::string>& FeedSpeedCsvColumns();
const std::vector<std::string>& GearCsvColumns();

// --- inspect -------------------------------------------------------------------------------
struct InspectCommandOptions {
  std::string input;  // an image, a directory of images or a video
  int frame = 0;      // which frame of it
  std::string out_png = "inspect.png";
  vision::StrandMeasureOptions strand;  // roi, polarity; the target when target_given
  bool target_given = false;            // else: strand, or filament when no tip is in view
  bool band_given = false;              // the strand's band fields hold the user's band (px)
  bool Validate(std::string* why) const;
};

struct InspectReport {
  vision::MeasureTarget target = vision::MeasureTarget::kStrand;
  vision::SceneResult scene;
  vision::StrandMeasurement measurement;
  cv::Rect frame_rect, suggested_roi;  // empty ROI: none to suggest
  std::string text;                    // the report, with the suggested command and manifest keys
};

// Looks at one frame as `measure` would and explains what it found: every candidate edge pair
// with its score and verdict, the chosen one, tip, band and calipers (an annotated PNG at
// out_png, written atomically), and a suggested command line and manifest snippet. Throws
// std::invalid_argument for an input that cannot be read or has no such frame.
InspectReport InspectInput(const InspectCommandOptions& options);

// --- calibrate -----------------------------------------------------------------------------
struct CalibrateCommandOptions {
  std::string pins_csv;                        // pin gauges: image,diameter_um[,tolerance_um]
  std::vector<std::string> micrometer_images;  // or stage micrometer images
  double pitch_um = 0;                         // micrometer line pitch
  bool fit_distortion = false;                 // micrometer: second-order term
  std::optional<double>
      expect_scale_um_per_px;                // micrometer: refuse a pitch that gives far from this
  std::string out;                           // calibration YAML
  std::string plot;                          // residual plot PNG; empty: next to out
  vision::StrandMeasureOptions pin_measure;  // roi, polarity for the pins
  bool Validate(std::string* why) const;
};

struct CalibrateResult {
  calib::ScaleCalibration calibration;
  std::vector<std::string> inputs;  // files read
};

// Measures the reference images and fits the scale; writes nothing. Throws std::invalid_argument
// naming the image or CSV row for bad input (unreadable image, pin or lines not found, missing
// diameter, too few targets, a pitch that does not fit).
CalibrateResult ComputeCalibration(const CalibrateCommandOptions& options);

// --- predict -------------------------------------------------------------------------------
struct PredictCommandOptions {
  std::string extruder = "direct-pla";  // preset name or YAML file
  std::vector<std::string> set;         // "name=value" overrides, applied in order
  std::string diameters;                // diameter table CSV (step, temperature_c, mean_um, …)
  std::string out_dir = "predict-out";
  std::string fit_measured;             // measured CSV; empty: no fit
  std::vector<std::string> fit_params;  // names of the unknowns
  bool plots = true;
  bool Validate(std::string* why) const;
};

struct PredictResult {
  model::ExtruderParams params;  // as loaded and overridden (the fit's start)
  std::vector<model::StepInput> steps;
  std::optional<model::FitSummary> fit;
  model::Prediction prediction;  // with the fitted parameters when a fit was asked for and usable
};

// Reads the inputs, fits when asked and predicts; writes nothing. Throws std::invalid_argument
// naming the file, row or parameter for bad input. A fit that is not usable comes back with
// fit->usable false and no prediction.
PredictResult ComputePrediction(const PredictCommandOptions& options);

// Writes predictions.csv/.json, plots, and with a fit fitted_params.yaml and fit_residuals.png into
// out_dir, each atomically. Returns the files written; plot problems go to `warnings`.
std::vector<std::string> WritePredictionOutputs(const PredictResult& result,
                                                const std::string& out_dir, bool plots,
                                                std::vector<std::string>* warnings);

// The extruder preset or YAML file with "name=value" overrides applied in order, validated. Throws
// std::invalid_argument naming --set or the parameter.
model::ExtruderParams LoadExtruderWithOverrides(const std::string& extruder,
                                                const std::vector<std::string>& set);

// --- thermal -------------------------------------------------------------------------------
struct ThermalCommandOptions {
  std::string material;                  // pla or abs
  std::vector<double> fan_velocity_m_s;  // assess these
  std::vector<double> t4_c;              // and these measured heat-sink temperatures
  std::string diameters;                 // optional: L_crt at every step of a diameter table
  std::string extruder = "direct-pla";
  std::vector<std::string> set;
  std::optional<double> filament_modulus_pa;  // else the extruder's filament_modulus_pa
  std::optional<double> viscosity_pa_s;       // else the study's value for the material
  std::optional<double> hp_length_mm;         // else the exit capillary (zone 3) length
  std::string out_dir;                        // empty: print only
  bool Validate(std::string* why) const;
};

struct ThermalReport {
  std::vector<model::ThermalAssessment> assessments;
  std::optional<model::SofteningOptions> softening_options;
  std::vector<model::SofteningStep> softening;
};

// Assesses every velocity and T4 and, with a diameter table, computes L_crt per step. Throws
// std::invalid_argument naming the option or file for bad input.
ThermalReport ComputeThermal(const ThermalCommandOptions& options);

// --- drive ---------------------------------------------------------------------------------
struct DriveCommandOptions {
  model::DriveOptions drive;
  std::optional<double> feed_force_n;         // one operating point
  std::optional<double> filament_speed_mm_s;  // for the velocity form at that point
  std::string diameters;                      // or every step of a diameter table
  std::string extruder = "direct-pla";
  std::vector<std::string> set;
  std::string out_dir;  // empty: print only
  bool Validate(std::string* why) const;
};

// Per-step slip from a diameter table (its slip_pct column, when present, as measured). Throws
// std::invalid_argument for bad input.
model::DrivePrediction ComputeDrive(const DriveCommandOptions& options);

// --- lag -----------------------------------------------------------------------------------
struct LagCommandOptions {
  std::string commanded;  // profile CSV: time_s, flow_mm3_s or filament_speed_mm_s
  model::ProfileForm profile_form = model::ProfileForm::kMoves;
  double filament_diameter_mm = 1.75;
  std::string frames;         // measure's frames CSV: fit K to it
  std::optional<double> k_s;  // or simulate with this K
  double k_la_s = 0;          // simulation: linear advance
  double dt_s = 0.001;        // simulation step
  model::LagFitOptions fit;
  std::string out_dir = "lag-out";
  bool plots = true;
  bool Validate(std::string* why) const;
};

struct LagReport {
  model::FlowProfile commanded;
  model::WidthSeries widths;                               // fit only
  std::optional<model::LagFitSummary> fit;                 // fit only
  std::vector<double> times, outlet, outlet_with_advance;  // simulation only
};

// Fits K to the frames, or simulates; writes nothing. Throws std::invalid_argument for bad input.
LagReport ComputeLag(const LagCommandOptions& options);
// lag.json, lag_fit.csv and lag_fit.png (fit) or outlet.csv and outlet.png (simulation), each
// written atomically. Plot problems go to `warnings`.
std::vector<std::string> WriteLagOutputs(const LagReport& report, const LagCommandOptions& options,
                                         std::vector<std::string>* warnings);

// --- experiments: measure --manifest, and run ----------------------------------------------
struct ExperimentCommandOptions {
  std::string manifest;
  std::string out_dir;
  std::optional<int> samples;  // overrides the manifest
  int jobs = 0;                // 0: all cores
  bool resume = false;
  std::optional<double> scale_um_per_px;  // overrides the manifest's scale or calibration
  std::string calib_path;
  bool full_pipeline = false;  // run: calibrate when the manifest says, measure, predict, summary
  // How frames are measured (`measure --manifest` takes them from its command line): the caliper,
  // blur, contrast and shading settings as they are; the ROI, polarity and target when given, else
  // the manifest's; each part of the band asked for here replaces the manifest's.
  vision::StrandMeasureOptions strand;
  bool roi_given = false, polarity_given = false, target_given = false;
  BandRequest band;
  std::string overlay_dir;  // empty: OUT/overlays
  bool Validate(std::string* why) const;
};

struct ExperimentReport {
  pipeline::Manifest manifest;
  std::vector<pipeline::StepResult> steps;
  std::optional<calib::ScaleCalibration> conversion;
  std::optional<PredictResult> prediction;
  std::vector<std::string> files;  // written
  std::vector<std::string> warnings;
  bool cancelled = false;
};

// Loads the manifest, calibrates (run only, when the manifest names reference images), measures
// every step, writes the tables, and (run only) predicts and writes summary.md/.json. `cancel`
// stops it early; finished steps are kept and their tables written. Throws std::invalid_argument
// for a bad manifest or options; a step that fails is reported in its row.
ExperimentReport RunExperimentCommand(const ExperimentCommandOptions& options,
                                      std::atomic<bool>* cancel);

// The command-line side shared by `run` and `measure --manifest`: Ctrl-C handling, the printed
// table, the exit status.
int RunExperimentCli(const ExperimentCommandOptions& options);

// --- watch ---------------------------------------------------------------------------------
struct WatchCommandOptions {
  // The measurement as `measure` has it (scale or calibration, ROI, band, target, polarity…);
  // its inputs are not used.
  MeasureCommandOptions measure;
  // Source, its timeouts, the rolling window and thresholds, report interval, duration. Its
  // strand, conversion and extruder are filled from the fields here.
  pipeline::LiveWatchOptions live;
  std::string extruder;                 // preset or YAML: attaches the clog index; empty: none
  std::vector<std::string> set;         // "name=value" overrides of the extruder
  std::optional<double> temperature_c;  // the nozzle's; default the extruder's reference
  std::string log_path;                 // JSON lines appended here; empty: standard output
  std::string http;                     // HOST:PORT for /status, /metrics, /frame.jpg
  std::string on_alert;                 // shell command run on every level change
};

struct WatchReport {
  pipeline::LiveWatchSummary summary;
  int http_port = 0;  // the bound port (useful with --http HOST:0)
  std::vector<std::string> alert_failures;
};

// Watches a camera, stream, file or folder until *stop (or the file's end, or --duration-s),
// writing JSON lines, serving HTTP and running the alert command. Throws std::invalid_argument
// (one line naming the option, file or source) when nothing can be watched: bad options, a source
// that cannot be opened or yields no frame, a log that cannot be opened, a port in use.
// `on_started`, when given, is called once the HTTP server listens (before the source opens).
WatchReport WatchNozzle(const WatchCommandOptions& options, std::atomic<bool>* stop,
                        const std::function<void(int http_port)>& on_started = {});

}  // namespace clogscope::apps
