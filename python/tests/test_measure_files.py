"""measure(), run_experiment() and feed_speed() against rendered truth, and their errors."""

import numpy as np
import pandas as pd
import pytest

import clogscope
from conftest import data_lines

WIDTHS_UM = (400.0, 381.3)


@pytest.fixture(scope="module")
def steps(tmp_path_factory):
    """Two rendered steps (folders of 6 PNGs each, 2 µm of jitter) and their manifest."""
    root = tmp_path_factory.mktemp("experiment")
    for i, w in enumerate(WIDTHS_UM):
        clogscope.render_to_files(root / f"step{i + 1}",
                                  clogscope.SceneParams(strand_width_um=w, width_jitter_um=2,
                                                        seed=40 + i), frames=6)
    (root / "experiment.yaml").write_text(
        "name: python test\nsamples: 5\nscale_um_per_px: 3.0\nsteps:\n"
        "  - {step: 1, temperature_c: 220, images: step1/}\n"
        "  - {step: 2, temperature_c: 210, images: step2/}\n")
    return root


def test_measure_a_folder_in_microns_against_the_truth(steps):
    frames, summary = clogscope.measure(steps / "step1", scale_um_per_px=3.0)
    truth = pd.read_json(steps / "step1" / "truth.json", typ="series")["frames"]
    truth_um = np.array([f["width_um"] for f in truth])
    assert summary.frames == 6 and summary.valid_frames == 6 and summary.inputs_failed == 0
    assert list(frames.columns[:8]) == ["source", "frame", "time_s", "valid", "width_px",
                                        "width_sigma_px", "width_um", "width_sigma_um"]
    assert np.max(np.abs(frames["width_um"].to_numpy() - truth_um)) < 0.3  # 0.1 px at 3 µm/px


def test_measure_with_a_calibration_converts_as_the_command_line(steps, run_cli, tmp_path):
    cal = clogscope.ScaleCalibration(3.0, 0.001, edge_bias_px=0.2, edge_bias_sigma_px=0.01)
    path = tmp_path / "calib.yaml"
    cal.save(path)
    frames, _ = clogscope.measure(steps / "step2", calibration=cal, band_start_um=60)
    out = tmp_path / "frames.csv"
    run_cli("measure", steps / "step2", "--calib", path, "--band-start-um", "60",
            "--out-frames", out)
    assert data_lines(frames.attrs["csv"]) == data_lines(out.read_text())
    assert any("calibration given" in c for c in frames.attrs["comments"])
    row = frames.iloc[0]
    assert row["width_um"] == pytest.approx((row["width_px"] - 0.2) * 3.0, abs=0.002)


def test_measure_reports_an_unreadable_input_and_goes_on(steps, tmp_path):
    frames, summary = clogscope.measure([tmp_path / "nothing.png", steps / "step1"])
    assert summary.inputs_failed == 1 and summary.inputs_ok == 1 and len(frames) == 6
    assert "nothing.png" in summary.errors[0]


def test_measure_refuses_options_with_the_command_lines_message(steps, run_cli):
    with pytest.raises(ValueError, match="band_start_um: a band in µm needs a pixel scale"):
        clogscope.measure(steps / "step1", band_start_um=50)
    with pytest.raises(ValueError, match="give either --scale-um-per-px or --calib, not both"):
        clogscope.measure(steps / "step1", scale_um_per_px=3,
                          calibration=clogscope.ScaleCalibration(3))
    # The options' band counts as band_*_px (the band's own check names it).
    with pytest.raises(ValueError, match=r"^band_height_px: the band height \(2.00 px\) must be "
                                         r"at least 4 px$"):
        clogscope.measure(steps / "step1", clogscope.MeasureOptions(band_height_px=2))
    with pytest.raises(ValueError, match="^max blur must be positive$") as e:
        clogscope.measure(steps / "step1", clogscope.MeasureOptions(max_blur_px=0))
    proc = run_cli("measure", steps / "step1", "--max-blur-px", "0", check=False)
    assert proc.stderr.strip() == f"clogscope measure: error: {e.value}"


def test_run_experiment_against_the_truth_and_the_command_line(steps, run_cli, tmp_path):
    diameters, report = clogscope.run_experiment(steps / "experiment.yaml", tmp_path / "py")
    assert list(diameters["step"]) == [1, 2]
    assert [s.status for s in report.steps] == ["ok", "ok"]
    for (_, row), width in zip(diameters.iterrows(), WIDTHS_UM):
        assert row["n"] == 5
        # The mean of 5 frames with 2 µm of jitter: within its 95 % interval (plus the 0.1 px
        # the measurement may be off) of the rendered width.
        assert abs(row["mean_um"] - width) < row["ci95_um"] + 0.3
    run_cli("measure", "--manifest", steps / "experiment.yaml", "--out", tmp_path / "cli")
    assert data_lines((tmp_path / "cli" / "diameters.csv").read_text()) == data_lines(
        (tmp_path / "py" / "diameters.csv").read_text())
    with pytest.raises(ValueError):
        clogscope.run_experiment(tmp_path / "missing.yaml", tmp_path / "x")


def test_feed_speed_between_two_frames_is_the_rendered_speed():
    scene = clogscope.feedstock_scene(2.0)  # 2 mm/s at 20 µm/px and 30 frames/s: 3.33 px/frame
    images, truth = clogscope.render(scene, frames=2)
    dt = truth["time_s"][1] - truth["time_s"][0]
    shift = clogscope.feed_speed(images[0], images[1], dt, scale_um_per_px=20)
    assert shift.valid, shift
    true_shift = truth["feed_offset_px"][1] - truth["feed_offset_px"][0]
    assert abs(shift.shift_px - true_shift) < max(4 * shift.sigma_px, 0.05)
    assert shift.speed_mm_s == pytest.approx(2.0, rel=0.02)
    still = clogscope.feed_speed(images[0], images[0], dt)
    assert still.valid and abs(still.shift_px) < 1e-6
    with pytest.raises(ValueError, match="dt_s"):
        clogscope.feed_speed(images[0], images[1], 0)
    with pytest.raises(ValueError, match="frame_b: not the size and type of frame_a"):
        clogscope.feed_speed(images[0], images[1][:100], dt)
