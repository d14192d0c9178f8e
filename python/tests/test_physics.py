"""The predictor and the clog physics against closed-form physics written out here, and fits
against the values the data were made with."""

import math

import numpy as np
import pytest

import clogscope


def test_predicted_back_pressure_is_the_power_law_tube_flow():
    p = clogscope.load_extruder("direct-pla")
    steps = [clogscope.StepInput(1, p.get("reference_temperature_c"), diameter_um=400),
             clogscope.StepInput(2, 200.0, diameter_um=350)]
    pred = clogscope.predict(p, steps)
    K, n = p.get("consistency_pa_sn"), p.get("flow_index")
    Q = p.get("print_speed_m_s") * p.get("layer_height_m") * p.get("nozzle_diameter_m")
    for step, sp in zip(steps, pred.steps):
        R = step.diameter_m / 2
        # Capillary of a power-law fluid: ΔP = 2 K L / R · ((3n + 1)/n · Q / (π R³))^n.
        dp3 = 2 * K * p.get("zone3_length_m") / R * ((3 * n + 1) / n * Q / (math.pi * R**3))**n
        assert sp.dp3_pa == pytest.approx(dp3, rel=1e-12)
        t, t0 = sp.temperature_c + 273.15, p.get("reference_temperature_c") + 273.15
        arrhenius = math.exp(p.get("activation_temperature_k") * (1 / t - 1 / t0))
        assert sp.dp_total_pa == pytest.approx((sp.dp1_pa + sp.dp2_pa + dp3) * arrhenius, rel=1e-12)
        area = math.pi * p.get("filament_diameter_m")**2 / 4
        assert sp.f_bp_n == pytest.approx(sp.dp_total_pa * area, rel=1e-12)
    assert pred.feed_force_n == pytest.approx(
        2 * p.get("motor_torque_nm") / p.get("drive_roller_radius_m"), rel=1e-12)
    table = clogscope.prediction_table(pred)
    assert list(table["step"]) == [1, 2] and table["dp_total_pa"].is_monotonic_increasing


def test_fit_recovers_the_consistency_the_currents_were_made_with():
    truth = clogscope.load_extruder("direct-pla", ["current_offset_ma=400",
                                                   "current_gain_ma_per_n=10"])
    true_k = 1.7 * truth.get("consistency_pa_sn")
    truth.set("consistency_pa_sn", true_k)
    steps = [clogscope.StepInput(i + 1, 220 - 10 * i, diameter_um=d)
             for i, d in enumerate([400, 390, 375, 355])]
    currents = [s.current_ma for s in clogscope.predict(truth, steps).steps]
    measured = [clogscope.MeasuredResponse(s.step, current_ma=c) for s, c in zip(steps, currents)]
    start = clogscope.load_extruder("direct-pla", ["current_offset_ma=400",
                                                   "current_gain_ma_per_n=10"])
    assert start.get("consistency_pa_sn") != pytest.approx(true_k, rel=0.1)
    fit = clogscope.fit_parameters(start, steps, measured, ["consistency_pa_sn"])
    assert fit.usable, fit.message
    assert fit.values[0].name == "consistency_pa_sn"
    assert fit.values[0].value == pytest.approx(true_k, rel=1e-4)
    assert fit.fitted.get("consistency_pa_sn") == pytest.approx(true_k, rel=1e-4)


def test_thermal_closed_forms():
    E, R, dp = 3.0e6, 0.875e-3, 2.0e6
    assert clogscope.critical_softened_length_m(E, R, dp) == pytest.approx(
        math.sqrt(math.pi**2 * E * R**2 / (4 * dp)), rel=1e-14)
    mu, q, length, r = 100.0, 2e-9, 0.8e-3, 0.2e-3
    assert clogscope.hagen_poiseuille_pressure_pa(mu, q, length, r) == pytest.approx(
        8 * mu * q * length / (math.pi * r**4), rel=1e-14)
    # The temperature a velocity gives leads back to that velocity (the inverse's own solver).
    a = clogscope.assess_fan_velocity("pla", 0.8)
    b = clogscope.assess_heat_sink_temperature("pla", a.t4_c)
    assert b.velocity_m_s == pytest.approx(0.8, abs=1e-9)
    assert isinstance(a.risk, clogscope.ClogRisk)
    with pytest.raises(ValueError):
        clogscope.assess_fan_velocity("pla", -1)
    with pytest.raises(ValueError, match="pla or abs|pla|abs"):
        clogscope.assess_fan_velocity("nylon", 1)


def test_slip_is_the_studys_formula():
    roller = clogscope.roller_presets()[0]
    fp, ff, kp = 60.0, 20.0, 0.5
    s = clogscope.slip(roller.name, fp, ff, k_p_pct=kp)
    assert s.pct == pytest.approx(kp + (roller.k_s_pct_n / fp**2 + roller.k_pct_per_n) * ff,
                                  rel=1e-12)
    with pytest.raises(ValueError):
        clogscope.slip(roller.name, 0.0, ff)


def test_lag_simulation_is_the_first_order_step_response():
    k = 0.2
    profile = clogscope.FlowProfile([0.0, 1.0, 1.0, 3.0], [2.0, 2.0, 5.0, 5.0])
    t = np.linspace(0.0, 3.0, 61)
    times, out = clogscope.simulate_lag(profile, k, times_s=list(t))
    expected = np.where(t < 1.0, 2.0, 5.0 - 3.0 * np.exp(-(t - 1.0) / k))
    assert np.max(np.abs(np.array(out) - expected)) < 1e-12


def test_lag_fit_recovers_k():
    k, gain = 0.15, 40.0
    profile = clogscope.FlowProfile([0.0, 1.0, 1.0, 2.5, 2.5, 4.0], [2.0, 2.0, 6.0, 6.0, 3.0, 3.0])
    t = np.arange(0.0, 4.0, 0.04)
    rng = np.random.default_rng(1)
    _, flow = clogscope.simulate_lag(profile, k, times_s=list(t))
    width = gain * np.array(flow) + rng.normal(0, 0.5, t.size)
    fit = clogscope.fit_lag(profile, list(t), list(width))
    assert fit.usable, fit.message
    assert abs(fit.k_s - k) < 4 * fit.k_sigma_s + 1e-3
    assert fit.gain == pytest.approx(gain, rel=0.01)
    with pytest.raises(ValueError, match="8"):
        clogscope.fit_lag(profile, [0.0, 1.0], [1.0, 2.0])


def test_predict_table_raises_the_command_lines_message(run_cli, tmp_path):
    missing = tmp_path / "none.csv"
    with pytest.raises(ValueError) as e:
        clogscope.predict_table(missing)
    proc = run_cli("predict", "--diameters", missing, "--out", tmp_path / "p", check=False)
    assert proc.stderr.strip() == f"clogscope predict: error: {e.value}"


def test_critical_lengths_buckle_under_the_predicted_back_pressure():
    p = clogscope.load_extruder("direct-pla")
    steps = [clogscope.StepInput(1, 220.0, diameter_um=400), clogscope.StepInput(2, 190.0,
                                                                                 diameter_um=360)]
    E, mu = 3.0e6, 100.0
    lengths = clogscope.critical_lengths(p, steps, modulus_pa=E, viscosity_pa_s=mu)
    pred = clogscope.predict(p, steps)
    R = p.get("filament_diameter_m") / 2
    Q = p.get("print_speed_m_s") * p.get("layer_height_m") * p.get("nozzle_diameter_m")
    for step, sp, lc in zip(steps, pred.steps, lengths):
        assert lc.dp_power_law_pa == pytest.approx(sp.dp_total_pa, rel=1e-12)
        # Euler buckling, pin-ended: L = √(π² E R² / (4 ΔP)).
        assert lc.l_crt_power_law_mm == pytest.approx(
            1e3 * math.sqrt(math.pi**2 * E * R**2 / (4 * sp.dp_total_pa)), rel=1e-12)
        r = step.diameter_m / 2
        assert lc.dp_hagen_poiseuille_pa == pytest.approx(
            8 * mu * Q * p.get("zone3_length_m") / (math.pi * r**4), rel=1e-12)
    assert lengths[1].l_crt_power_law_mm < lengths[0].l_crt_power_law_mm  # clogged: shorter


def test_drive_slip_at_each_step_is_the_formula_at_its_feed_force():
    p = clogscope.load_extruder("direct-pla")
    steps = [clogscope.StepInput(1, 220.0, diameter_um=400), clogscope.StepInput(2, 200.0,
                                                                                 diameter_um=350)]
    drive = clogscope.predict_drive(p, steps, pinch_force_n=70, friction_n=2.0)
    pred = clogscope.predict(p, steps)
    roller = drive.roller
    for ds, sp in zip(drive.steps, pred.steps):
        assert ds.f_bp_n == pytest.approx(sp.f_bp_n, rel=1e-12)
        assert ds.feed_force_n == pytest.approx(sp.f_bp_n + 2.0, rel=1e-12)
        assert ds.slip_pinch.pct == pytest.approx(
            (roller.k_s_pct_n / 70**2 + roller.k_pct_per_n) * ds.feed_force_n, rel=1e-12)
        assert ds.delivered_flow_mm3_s == pytest.approx(
            (1 - ds.slip_pinch.pct / 100) * ds.commanded_flow_mm3_s, rel=1e-12)
