"""The same frames measured from Python and by the command line give the same table, to the
byte: measure() runs the command's own function, measure_frame and Tracker the functions the
command runs per image and per video frame."""

import numpy as np
import pandas as pd
import pytest

import clogscope
from conftest import data_lines

FRAMES = ["bright_tilt5.png", "silhouette_tilt-12.png", "colour_bed.png"]


@pytest.fixture(scope="module")
def inputs(testdata):
    return [testdata / "frames" / f for f in FRAMES] + [testdata / "video" / "jitter_sway.mp4"]


@pytest.fixture(scope="module")
def cli_table(inputs, run_cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "frames.csv"
    run_cli("measure", *inputs, "--scale-um-per-px", "3", "--out-frames", out)
    return out.read_text(encoding="utf-8")


def test_measure_writes_the_command_lines_table(inputs, cli_table):
    frames, summary = clogscope.measure(inputs, scale_um_per_px=3)
    assert data_lines(frames.attrs["csv"]) == data_lines(cli_table)
    pd.testing.assert_frame_equal(frames, clogscope.read_frames_table(cli_table))
    assert summary.frames == len(frames) == 3 + 25
    assert summary.valid_frames == int(frames["valid"].sum())
    assert summary.valid_frames >= 25  # the reference frames are measurable


def test_measure_frame_gives_the_command_lines_numbers(testdata, cli_table):
    cli = clogscope.read_frames_table(cli_table)
    for name in FRAMES:
        path = testdata / "frames" / name
        row = cli[cli["source"] == str(path)].iloc[0]
        m = clogscope.measure_frame(clogscope.read_image(path))
        assert m.valid and row["valid"] == 1
        # The table's own rounding of the Python numbers, compared as text: exact.
        assert f"{m.width_px:.4f}" == f"{row['width_px']:.4f}"
        assert f"{m.width_sigma_px:.4f}" == f"{row['width_sigma_px']:.4f}"
        assert f"{m.angle_deg:.3f}" == f"{row['angle_deg']:.3f}"
        assert f"{m.tip_x_px:.2f}" == f"{row['tip_x_px']:.2f}"
        assert m.calipers_used == row["calipers_used"]
        assert m.polarity.name == row["polarity"]


def test_tracker_over_a_video_gives_the_command_lines_numbers(testdata, run_cli, tmp_path):
    video = testdata / "video" / "jitter_sway.mp4"
    out = tmp_path / "frames.csv"
    run_cli("measure", video, "--no-outlier-flags", "--out-frames", out)
    cli = clogscope.read_frames_table(out)
    frames = clogscope.open_frames(video)
    assert frames.encoder.found  # x264 wrote it: each width carries the codec's doubt
    tracker = clogscope.Tracker(encoder=frames.encoder)
    rows = []
    for f in frames:
        assert f.luma_range == clogscope.LumaRange.limited  # H.264's luma as stored: 16-235
        rows.append((f.index, f.time_s, tracker.measure(f.image, luma_range=f.luma_range)))
    assert len(rows) == len(cli) == 25
    assert tracker.tracked_frames > 0  # it did track, not search afresh every frame
    for (index, time_s, m), (_, row) in zip(rows, cli.iterrows()):
        assert index == row["frame"] and f"{time_s:.4f}" == f"{row['time_s']:.4f}"
        assert m.reason == ("" if pd.isna(row["reason"]) else row["reason"])
        if m.valid:
            assert f"{m.width_px:.4f}" == f"{row['width_px']:.4f}"
            assert f"{m.width_sigma_px:.4f}" == f"{row['width_sigma_px']:.4f}"


def test_render_draws_the_command_lines_frames(run_cli, tmp_path):
    out = tmp_path / "frames"
    run_cli("render", "--out", out, "--frames", "2", "--size", "320x240", "--tip-y-px", "60",
            "--tip-x-px", "160", "--strand-width-um", "250", "--tilt-deg", "3", "--colour",
            "--seed", "7")
    scene = clogscope.SceneParams(width_px=320, height_px=240, tip_x_px=160, tip_y_px=60,
                                  strand_width_um=250, tilt_deg=3, colour=True, seed=7)
    images, truth = clogscope.render(scene, frames=2)
    for i in range(2):
        from_cli = clogscope.read_image(out / f"frame_{i:06d}.png")
        assert from_cli.shape == images[i].shape == (240, 320, 3)
        assert np.array_equal(from_cli, images[i])
    assert truth["width_um"].tolist() == [250.0, 250.0]
