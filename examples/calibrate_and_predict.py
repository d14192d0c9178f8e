#!/usr/bin/env python3
"""Calibrate the pixel scale from pin gauges, then fit the clog predictor to a diameter table
and plot the measured motor current against the predicted one.

    PYTHONPATH=build/python /usr/bin/python3 examples/calibrate_and_predict.py \\
        [--pins pins.csv] [--diameters diameters.csv --measured measured.csv] [--out fit.png]

pins.csv: image,diameter_um (as `clogscope calibrate --pins`); diameters.csv: a diameter table
(`clogscope run`'s, or step,temperature_c,mean_um); measured.csv: step,current_ma (and/or
amplitude_m_s2). Without them it renders three pins and four temperature steps, measures the
steps with the calibration, and makes up a motor current from a stiffer melt than the preset's,
so the fit has something to find. The plot needs matplotlib (Debian: python3-matplotlib).
"""

import argparse
import pathlib
import tempfile

import numpy as np

import clogscope

EXTRUDER = ["current_offset_ma=400", "current_gain_ma_per_n=8"]  # the motor's I_0 and gain


def demo_pins(root):
    rows = ["image,diameter_um"]
    for d in (300, 400, 500):
        scene = clogscope.SceneParams(target=clogscope.RenderTarget.pin, strand_width_um=d,
                                      edge_bias_px=0.4, seed=d)
        clogscope.render_to_files(root / f"pin{d}", scene)
        rows.append(f"pin{d}/frame_000000.png,{d}")
    (root / "pins.csv").write_text("\n".join(rows) + "\n")
    return root / "pins.csv"


def demo_diameters(root, calibration_file):
    steps = [(220, 400.0), (210, 396.9), (200, 390.1), (190, 381.3)]
    lines = ["name: demo", "samples: 5", f"calibration: {calibration_file}", "steps:"]
    for i, (t, width) in enumerate(steps, 1):
        scene = clogscope.SceneParams(strand_width_um=width, width_jitter_um=2, edge_bias_px=0.4,
                                      seed=i)
        clogscope.render_to_files(root / f"step{i}", scene, frames=6)
        lines.append(f"  - {{step: {i}, temperature_c: {t}, images: step{i}/}}")
    (root / "experiment.yaml").write_text("\n".join(lines) + "\n")
    diameters, report = clogscope.run_experiment(root / "experiment.yaml", root / "results")
    return root / "results" / "diameters.csv"


def demo_measured(root, steps):
    # A made-up measurement: the predictor's current with a 1.4× stiffer melt, ±3 mA of noise.
    truth = clogscope.load_extruder("direct-pla", EXTRUDER)
    truth.set("consistency_pa_sn", 1.4 * truth.get("consistency_pa_sn"))
    rng = np.random.default_rng(0)
    rows = ["step,current_ma"]
    for s in clogscope.predict(truth, steps).steps:
        rows.append(f"{s.step},{s.current_ma + rng.normal(0, 3):.2f}")
    (root / "measured.csv").write_text("\n".join(rows) + "\n")
    return root / "measured.csv"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pins", type=pathlib.Path)
    parser.add_argument("--diameters", type=pathlib.Path)
    parser.add_argument("--measured", type=pathlib.Path)
    parser.add_argument("--out", default="fit.png", type=pathlib.Path)
    args = parser.parse_args()
    root = pathlib.Path(tempfile.mkdtemp(prefix="clogscope-demo-"))

    cal, _ = clogscope.calibrate_pins(args.pins or demo_pins(root))
    if not cal.usable:
        raise SystemExit(f"calibration not usable: {cal.message}")
    print(f"scale {cal.scale_um_per_px:.5f} ± {cal.scale_sigma_um_per_px:.5f} µm/px, "
          f"edge bias {cal.edge_bias_px:+.3f} ± {cal.edge_bias_sigma_px:.3f} px")
    print(clogscope.residual_table(cal).to_string(index=False))
    cal.save(root / "calib.yaml")

    params = clogscope.load_extruder("direct-pla", EXTRUDER)
    table = args.diameters or demo_diameters(root, root / "calib.yaml")
    steps = clogscope.read_diameter_table(table, params.get("reference_temperature_c"))
    print("\n" + clogscope.to_frame(steps, ["step", "temperature_c", "diameter_um"])
          .to_string(index=False))
    measured = args.measured or demo_measured(root, steps)

    run = clogscope.predict_steps(params, steps, measured_csv=measured,
                                  fit_params=["consistency_pa_sn"])
    if not run.fit.usable:
        raise SystemExit(f"fit not usable: {run.fit.message}")
    for v in run.fit.values:
        print(f"\n{v.name}: {v.initial:.4g} -> {v.value:.4g} ± {v.sigma:.2g}")
    predicted = clogscope.prediction_table(run.prediction)
    residuals = clogscope.to_frame(run.fit.residuals, ["step", "quantity", "measured", "model"])
    print(residuals.to_string(index=False))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        residuals.to_csv(args.out.with_suffix(".csv"), index=False)
        print(f"matplotlib is not installed (apt-get install python3-matplotlib): wrote "
              f"{args.out.with_suffix('.csv')} instead of a plot")
        return
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(residuals["measured"], residuals["model"], "o")
    lo, hi = residuals[["measured", "model"]].min().min(), residuals[["measured", "model"]].max().max()
    ax.plot([lo, hi], [lo, hi], "k--", lw=0.8)
    for _, r in residuals.iterrows():
        ax.annotate(f"step {r['step']}", (r["measured"], r["model"]), fontsize=8)
    ax.set_xlabel("measured motor current (mA)")
    ax.set_ylabel("predicted motor current (mA)")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}; predicted back-pressure per step:\n"
          f"{predicted[['step', 'diameter_um', 'dp_total_pa', 'current_ma']].to_string(index=False)}")


if __name__ == "__main__":
    main()
