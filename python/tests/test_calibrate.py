"""The pixel scale from rendered pins and a rendered micrometer, against the scale and edge
bias they were rendered with, and against `clogscope calibrate` on the same images."""

import math

import pytest

import clogscope

SCALE_UM_PER_PX = 3.0
EDGE_BIAS_PX = 0.4


@pytest.fixture(scope="module")
def pins(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pins")
    rows = ["image,diameter_um"]
    for d in (300, 350, 400, 450, 500):
        scene = clogscope.SceneParams(target=clogscope.RenderTarget.pin, strand_width_um=d,
                                      edge_bias_px=EDGE_BIAS_PX, seed=d)
        clogscope.render_to_files(folder / f"pin{d}", scene)
        rows.append(f"pin{d}/frame_000000.png,{d}")
    csv = folder / "pins.csv"
    csv.write_text("\n".join(rows) + "\n")
    return csv


def test_pins_give_the_rendered_scale_and_edge_bias(pins):
    cal, notes = clogscope.calibrate_pins(pins)
    assert cal.usable and cal.method == "pins" and len(notes) == 5
    assert abs(cal.scale_um_per_px - SCALE_UM_PER_PX) < 0.003  # 0.1 %
    assert abs(cal.edge_bias_px - EDGE_BIAS_PX) < 0.1
    assert 0 < cal.scale_sigma_um_per_px < 0.01
    table = clogscope.residual_table(cal)
    assert list(table["nominal_um"]) == [300, 350, 400, 450, 500]
    assert table["residual_px"].abs().max() < 0.1
    # Converting with it: a 400 µm pin's apparent width comes back as 400 µm.
    assert abs(cal.to_um(400 / SCALE_UM_PER_PX + EDGE_BIAS_PX) - 400) < 0.5


def test_pins_calibrate_as_the_command_line_does(pins, run_cli, tmp_path):
    out = tmp_path / "calib.yaml"
    run_cli("calibrate", "--pins", pins, "--out", out)
    cli = clogscope.read_calibration(out)
    cal, _ = clogscope.calibrate_pins(pins)
    # The file holds the numbers to its own precision: equal to that.
    assert cli.scale_um_per_px == pytest.approx(cal.scale_um_per_px, rel=1e-9)
    assert cli.edge_bias_px == pytest.approx(cal.edge_bias_px, abs=1e-9)
    assert cli.scale_sigma_um_per_px == pytest.approx(cal.scale_sigma_um_per_px, rel=1e-6)
    # And saved from Python, read back alike.
    cal.save(tmp_path / "py.yaml")
    back = clogscope.read_calibration(tmp_path / "py.yaml")
    assert back.scale_um_per_px == pytest.approx(cal.scale_um_per_px, rel=1e-12)


def test_micrometer_gives_the_rendered_scale(tmp_path):
    scene = clogscope.SceneParams(target=clogscope.RenderTarget.micrometer, scale_um_per_px=2.5,
                                  pitch_um=100, seed=4)
    clogscope.render_to_files(tmp_path / "micro", scene)
    cal, _ = clogscope.calibrate_micrometer([tmp_path / "micro" / "frame_000000.png"], 100)
    assert cal.usable and cal.method == "micrometer"
    assert abs(cal.scale_um_per_px - 2.5) < 0.0025  # 0.1 %
    assert cal.targets >= 10


def test_fit_pin_scale_solves_exact_widths():
    # width_px = d / s + b exactly: the fit must return s and b (closed form).
    s, b = 2.75, 0.3
    pins = [clogscope.PinObservation(d, d / s + b, 0.01) for d in (250, 300, 400, 550)]
    cal = clogscope.fit_pin_scale(pins)
    assert cal.scale_um_per_px == pytest.approx(s, rel=1e-7)
    assert cal.edge_bias_px == pytest.approx(b, abs=1e-6)


def test_calibration_errors_are_value_errors_with_the_command_lines_message(run_cli, tmp_path):
    missing = tmp_path / "none.csv"
    with pytest.raises(ValueError) as e:
        clogscope.calibrate_pins(missing)
    proc = run_cli("calibrate", "--pins", missing, "--out", tmp_path / "c.yaml", check=False)
    assert proc.returncode == 1
    assert proc.stderr.strip() == f"clogscope calibrate: error: {e.value}"
    with pytest.raises(ValueError, match="give diameter_um or diameter_m"):
        clogscope.StepInput(1, 200)
    with pytest.raises(ValueError, match="scale_um_per_px: must be a positive number"):
        clogscope.ScaleCalibration(-1)
    same = [clogscope.PinObservation(400, 133.7), clogscope.PinObservation(400, 133.8)]
    with pytest.raises(ValueError):
        clogscope.fit_pin_scale(same)
    assert math.isclose(clogscope.ScaleCalibration(3.0, edge_bias_px=0.5).to_um(100.5), 300.0)
