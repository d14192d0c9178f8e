#!/usr/bin/env python3
"""Measure every frame of a folder of images (or a video) and plot the strand width per frame
with its band of ±1σ.

    PYTHONPATH=build/python /usr/bin/python3 examples/measure_folder.py FOLDER_OR_VIDEO \\
        [--scale-um-per-px 3.0 | --calib calib.yaml] [--out width.png]

Without an input it renders a 20-frame demo folder first (a 390.1 µm strand, 2 µm of width
jitter) so the script runs as it is. The plot needs matplotlib (Debian: python3-matplotlib);
without it the table is written as CSV instead.
"""

import argparse
import pathlib
import tempfile

import clogscope


def demo_folder():
    folder = pathlib.Path(tempfile.mkdtemp(prefix="clogscope-demo-")) / "frames"
    scene = clogscope.SceneParams(strand_width_um=390.1, width_jitter_um=2, edge_bias_px=0.4)
    clogscope.render_to_files(folder, scene, frames=20)
    return folder


def plot(frames, unit, out):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        csv = out.with_suffix(".csv")
        frames.to_csv(csv, index=False)
        print(f"matplotlib is not installed (apt-get install python3-matplotlib): "
              f"wrote the table to {csv} instead of a plot")
        return
    valid = frames[frames["valid"] == 1]
    w, s = valid[f"width_{unit}"], valid[f"width_sigma_{unit}"]
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.fill_between(valid["frame"], w - s, w + s, alpha=0.3, label="±1σ")
    ax.plot(valid["frame"], w, "o-", ms=3, label="width")
    ax.set_xlabel("frame")
    ax.set_ylabel(f"strand width ({'µm' if unit == 'um' else 'px'})")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("input", nargs="?", help="folder of images or video (default: a demo)")
    parser.add_argument("--scale-um-per-px", type=float)
    parser.add_argument("--calib", help="calibration file from clogscope calibrate")
    parser.add_argument("--out", default="width.png", type=pathlib.Path)
    args = parser.parse_args()
    source = args.input or demo_folder()
    if not args.input and not args.calib and args.scale_um_per_px is None:
        args.scale_um_per_px = 3.0  # the demo's scale
    frames, summary = clogscope.measure(source, scale_um_per_px=args.scale_um_per_px,
                                        calibration=args.calib)
    print(f"{summary.valid_frames} of {summary.frames} frames valid")
    for reason, n in frames[frames["valid"] == 0]["reason"].value_counts().items():
        print(f"  {n} frame(s) {reason}")
    unit = "um" if frames["width_um"].notna().any() else "px"
    valid = frames[frames["valid"] == 1]
    if len(valid):
        print(f"width {valid[f'width_{unit}'].mean():.3f} {unit} mean, "
              f"{valid[f'width_{unit}'].std():.3f} frame to frame, "
              f"{valid[f'width_sigma_{unit}'].median():.3f} median σ")
    plot(frames, unit, args.out)


if __name__ == "__main__":
    main()
