"""pandas tables from the library's results: the per-frame table, rendered truth, calibration
residuals, predictions. Column names carry their units, as the command line's CSV files do."""

import io
import os

import pandas as pd

__all__ = ["read_frames_table", "to_frame", "truth_table", "residual_table", "prediction_table"]


def _split_comments(text):
    """The leading '# ...' lines (provenance, calibration) and the CSV after them."""
    comments = []
    rest = text
    while rest.startswith("#"):
        line, _, rest = rest.partition("\n")
        comments.append(line)
    return comments, rest


def read_frames_table(path_or_text):
    """Reads a per-frame table (``clogscope measure --out-frames``, or the text measure() made)
    into a DataFrame: the same columns, the same numbers as the file holds. Leading '#' lines
    (provenance, calibration) go to ``df.attrs['comments']``."""
    if isinstance(path_or_text, (str, os.PathLike)) and not str(path_or_text).startswith("#") \
            and "\n" not in str(path_or_text):
        with open(path_or_text, encoding="utf-8") as f:
            text = f.read()
    else:
        text = str(path_or_text)
    comments, csv = _split_comments(text)
    df = pd.read_csv(io.StringIO(csv))
    df.attrs["comments"] = comments
    return df


def _fields(obj):
    """The public data attributes of a result object (its methods left out)."""
    return [name for name in dir(type(obj))
            if not name.startswith("_") and not callable(getattr(obj, name))]


def to_frame(objects, columns=None):
    """A DataFrame with one row per result object (StepPrediction, TargetResidual, FrameTruth,
    SofteningStep, ...), one column per attribute (or those in `columns`, in that order). Enum
    values become their names."""
    objects = list(objects)
    if not objects:
        return pd.DataFrame(columns=columns or [])
    columns = columns or _fields(objects[0])
    rows = []
    for o in objects:
        row = {}
        for c in columns:
            v = getattr(o, c)
            row[c] = v.name if hasattr(v, "name") and hasattr(v, "value") else v
        rows.append(row)
    return pd.DataFrame(rows, columns=columns)


def truth_table(truths):
    """Rendered ground truth (FrameTruth list) as a DataFrame: frame, width_um, width_px,
    angle_deg, tip_x_px, tip_y_px, time_s, feed_offset_px, gear_angle_rad."""
    return to_frame(truths, ["frame", "width_um", "width_px", "angle_deg", "tip_x_px", "tip_y_px",
                             "time_s", "feed_offset_px", "gear_angle_rad"])


def residual_table(calibration):
    """A calibration's residual table: one row per pin or micrometer line."""
    return to_frame(calibration.residuals, ["name", "nominal_um", "measured_px", "model_px",
                                            "residual_px", "residual_um", "outlier"])


def prediction_table(prediction):
    """The predictor's table (predictor.md §8): one row per step of a Prediction."""
    return to_frame(prediction.steps, [
        "step", "temperature_c", "diameter_um", "dp1_pa", "dp2_pa", "dp3_pa", "dp_total_pa",
        "f_bp_n", "f_feed_n", "load_n", "relative_amplitude", "amplitude_increase_pct",
        "amplitude_m_s2", "natural_frequency_hz", "current_ma", "buckling_ratio",
        "filament_diameter_um"])
