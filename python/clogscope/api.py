"""The functions that take files, folders and videos, and return pandas tables: measure,
run_experiment, render. Each calls the command line's own typed function (see docs/python.md)."""

import os
import tempfile

import numpy as np
import pandas as pd

from . import _core
from .tables import read_frames_table, truth_table

__all__ = ["measure", "run_experiment", "render"]


def _paths(path_or_paths):
    if isinstance(path_or_paths, (str, os.PathLike)):
        return [os.fspath(path_or_paths)]
    return [os.fspath(p) for p in path_or_paths]


def measure(inputs, options=None, *, scale_um_per_px=None, calibration=None,
            band_start_um=None, band_height_um=None, band_start_px=None, band_height_px=None,
            overlay_dir=None, overlay_every=0, flag_outliers=True, speed=False,
            speed_options=None, gear_roi=None, gear_centre_px=None, gear_radius_mm=None):
    """Measures every frame of images, folders of images and videos, as
    ``clogscope measure INPUTS --out-frames`` does (the same function, pipeline::MeasureInputs).

    inputs: a path or a list of paths (images, folders of images, .mp4/.avi/... videos).
    options: MeasureOptions (roi, polarity, target, caliper, limits).
    scale_um_per_px or calibration (a ScaleCalibration, or the path of a calibration file):
        widths in µm too (width_um, width_sigma_um).
    band_start_um, band_height_um (need a scale) or band_start_px, band_height_px: the band
        below the tip; default 50 µm and 150 µm (a filament: its whole straight stretch).
        Band fields set in `options` count as band_*_px when no keyword is given.
    overlay_dir, overlay_every: annotated PNGs (every image, every 25th video frame).
    flag_outliers: mark widths far from their ±25 neighbours as width_outlier.
    speed, speed_options, gear_roi (x, y, w, h), gear_centre_px (x, y), gear_radius_mm: a
        moving filament's feed speed and the drive gear's slip (`measure --speed`).

    Returns (frames, summary): a pandas DataFrame with the columns of --out-frames (source,
    frame, time_s, valid, width_px, width_sigma_px, width_um, width_sigma_um, angle_deg,
    contrast, blur_px, tip_x_px, tip_y_px, calipers_used, calipers_total, polarity, reason,
    detail, and the speed columns), the numbers as the CSV holds them (width to 1e-4 px; for
    full precision measure arrays with measure_frame or Tracker), its '#' lines in
    frames.attrs['comments']; and a MeasureSummary (frames, valid_frames, errors: an input
    that cannot be read is reported there and skipped). The GIL is released while measuring.

    Raises ValueError with the command line's message for options that cannot be used.
    """
    if isinstance(calibration, os.PathLike):
        calibration = os.fspath(calibration)
    text, summary = _core._measure_inputs(
        _paths(inputs), options, scale_um_per_px, calibration, band_start_um, band_height_um,
        band_start_px, band_height_px, os.fspath(overlay_dir) if overlay_dir else "",
        overlay_every, flag_outliers, speed, speed_options,
        None if gear_roi is None else list(gear_roi),
        None if gear_centre_px is None else tuple(gear_centre_px), gear_radius_mm)
    frames = read_frames_table(text)
    frames.attrs["csv"] = text
    return frames, summary


def run_experiment(manifest, out_dir=None, *, samples=None, jobs=0, resume=False,
                   scale_um_per_px=None, calibration=None, full_pipeline=False, options=None):
    """Runs an experiment manifest, as ``clogscope measure --manifest`` (or ``clogscope run``
    with full_pipeline=True: calibrate from the manifest's targets, measure, predict,
    summarise), through pipeline::RunManifest.

    manifest: the YAML or CSV manifest. out_dir: where the tables go (frames.csv,
    diameters.csv, ...; default a new temporary folder, in report.files). samples: valid frames
    per step (overrides the manifest). jobs: steps at once (0: all cores). scale_um_per_px or
    calibration (a calibration file's path) override the manifest's. options: MeasureOptions;
    what differs from the defaults (roi, polarity, target, band) overrides the manifest.

    Returns (diameters, report): the diameter table (diameters.csv: step, temperature_c, n,
    mean_um, std_um, sem_um, ci95_um, cal_sigma_um, mean_px, std_px, ..., status, detail) as a
    DataFrame, and an ExperimentReport (steps: StepResult list; conversion; prediction;
    files). A step that fails is reported in its row; a bad manifest raises ValueError.
    """
    if out_dir is None:
        out_dir = tempfile.mkdtemp(prefix="clogscope-run-")
    report = _core._run_manifest(os.fspath(manifest), os.fspath(out_dir), samples, jobs, resume,
                                 scale_um_per_px, os.fspath(calibration) if calibration else "",
                                 full_pipeline, options)
    table = os.path.join(os.fspath(out_dir), "diameters.csv")
    diameters = read_frames_table(table) if os.path.exists(table) else pd.DataFrame()
    return diameters, report


def render(scene=None, frames=1, first=0):
    """Renders frames of a synthetic scene with exact ground truth (the renderer behind
    ``clogscope render``).

    scene: SceneParams (default: the reference scene, a 400 µm strand at 3 µm/px, 1280×720).
    frames, first: how many frames, from which index (the same scene, seed and index give the
    same image).

    Returns (images, truth): a NumPy array N×H×W (grey) or N×H×W×3 (BGR), uint8 or uint16, and
    a DataFrame with one row per frame (frame, width_um, width_px, angle_deg, tip_x_px,
    tip_y_px, time_s, feed_offset_px, gear_angle_rad). images[i] is a frame measure_frame
    takes as it is.
    """
    images, truths = _core._render(scene if scene is not None else _core.SceneParams(), frames,
                                   first)
    return images, truth_table(truths)
