"""Seeds for fuzz/campaign.py: one small input of every kind, made by `clogscope` itself (renders,
a calibration, a finished run with its step files) plus a JPEG cut from the MJPEG video and a
16-bit TIFF written here."""
import json
import math
import os
import shutil
import struct
import subprocess
import sys


class Seeds:
    """Inputs of every kind, made by the tool itself (and a few written here) under OUT/seeds."""

    def __init__(self, binary, root):
        self.bin = os.path.abspath(binary)
        self.root = os.path.abspath(root)
        self.files = {}

    def sh(self, *args):
        r = subprocess.run([self.bin, *args], cwd=self.root, capture_output=True, text=True)
        if r.returncode not in (0, 2):
            sys.exit(f"seed command failed: clogscope {' '.join(args)}\n{r.stdout}{r.stderr}")

    def write(self, name, data):
        path = os.path.join(self.root, name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(data if isinstance(data, bytes) else data.encode())
        return path

    def make(self):
        shutil.rmtree(self.root, ignore_errors=True)
        os.makedirs(self.root)
        small = ["--size", "320x240", "--tip-x-px", "160", "--tip-y-px", "60",
                 "--scale-um-per-px", "10"]
        self.sh("render", "--out", "frames", "--frames", "2", *small)
        self.sh("render", "--out", "frames16", "--bit-depth", "16", *small)
        self.sh("render", "--out", "colour", "--colour", "--no-nozzle", *small)
        self.sh("render", "--out", "step1.mp4", "--frames", "12", "--fps", "10", *small)
        self.sh("render", "--out", "step2.avi", "--frames", "12", "--fps", "10",
                "--strand-width-um", "380", *small)
        self.sh("render", "--out", "micro", "--target", "micrometer", "--size", "640x120",
                "--scale-um-per-px", "5")
        for d in (300, 400, 500):
            self.sh("render", "--out", f"pin{d}", "--target", "pin", "--strand-width-um", str(d),
                    "--size", "320x240", "--tip-x-px", "160", "--tip-y-px", "120",
                    "--scale-um-per-px", "5")
        self.write("pins.csv", "image,diameter_um,tolerance_um\n" + "".join(
            f"{self.root}/pin{d}/frame_000000.png,{d},0.5\n" for d in (300, 400, 500)))
        self.sh("calibrate", "--pins", "pins.csv", "--out", "calib.yaml", "--plot", "calib.png")
        # A JPEG: the first frame of the MJPEG video. A TIFF: 16-bit, 12-bit data, written here.
        avi = open(os.path.join(self.root, "step2.avi"), "rb").read()
        a = avi.find(b"\xff\xd8\xff")
        self.write("frame.jpg", avi[a:avi.find(b"\xff\xd9", a) + 2])
        self.write("frame.tif", tiff16(160, 120))
        self.write("temps.csv", "time_s,temperature_c\n" + "".join(
            f"{t * 0.2:.1f},{220 if t < 6 else 210}\n" for t in range(12)))
        self.write("experiment.yaml", f"""name: campaign
samples: 3
settle_s: 0.1
scale_um_per_px: 10
calibration: {self.root}/calib.yaml
extruder: direct-pla
steps:
  - {{step: 1, temperature_c: 220, video: {self.root}/step1.mp4}}
  - {{step: 2, temperature_c: 210, video: {self.root}/step2.avi, start_s: 0.2}}
  - {{step: 3, temperature_c: 200, images: {self.root}/frames}}
""")
        self.write("logged.yaml", f"""name: logged
samples: 2
scale_um_per_px: 10
temperature_log: {self.root}/temps.csv
hold_tolerance_c: 1
min_step_s: 0.5
video: {self.root}/step1.mp4
""")
        self.write("steps.csv", "step,temperature_c,source,start_s,end_s\n"
                   f"1,220,{self.root}/step1.mp4,0,\n2,210,{self.root}/step2.avi,0.1,1.0\n"
                   f"3,200,{self.root}/frames\n")
        self.write("extruder.yaml", "base: direct-pla\nconsistency_pa_sn: 5000\nflow_index: 0.4\n"
                   "damping_ratio: 0.04\nload_model: sum\n")
        self.sh("run", "experiment.yaml", "--out", "runout")
        self.write("fit.csv", "step,amplitude_m_s2,current_ma\n1,0.5,600\n2,0.6,620\n3,0.7,650\n")
        self.make_newer()
        steps = sorted(os.listdir(os.path.join(self.root, "runout", "steps")))
        kinds = {
            "manifest_yaml": ["experiment.yaml", "logged.yaml"],
            "manifest_csv": ["steps.csv"],
            "temperature_log": ["temps.csv"],
            "pins_csv": ["pins.csv"],
            "calibration_yaml": ["calib.yaml"],
            "diameters_csv": ["runout/diameters.csv"],
            "fit_csv": ["fit.csv"],
            "extruder_yaml": ["extruder.yaml"],
            "step_json": [f"runout/steps/{s}" for s in steps],
            "image": ["frames/frame_000000.png", "frames16/frame_000000.png",
                      "colour/frame_000000.png", "frame.jpg", "frame.tif"],
            "micrometer_image": ["micro/frame_000000.png"],
            "video": ["step1.mp4", "step2.avi"],
            # The newer surfaces (issue 27).
            "lag_frames": ["lag_frames.csv", "measured_frames.csv"],
            "lag_profile": ["profile.csv", "profile_speed.csv"],
            "thermal": ["runout/diameters.csv", "drive.csv"],
            "drive": ["drive.csv", "runout/diameters.csv"],
            "feedstock_manifest": ["feed.yaml", "feed_steps.yaml"],
            "filament_speed": ["feed.avi", "feed.mp4"],
            "inspect": ["frames/frame_000000.png", "frame.jpg", "step1.mp4", "feed.avi"],
            "watch_file": ["step1.mp4", "step2.avi"],
            "watch_folder": ["frames/frame_000000.png", "frames16/frame_000000.png", "frame.jpg",
                             "frame.tif"],
        }
        for k, names in kinds.items():
            self.files[k] = [os.path.join(self.root, n) for n in names]
        json.dump(self.files, open(os.path.join(self.root, "seeds.json"), "w"), indent=1)

    def make_newer(self):
        """Seeds of the newer commands: lag profiles and frames, drive tables, a filament video
        with its drive gear, manifests with a feedstock block."""
        self.write("profile.csv", "time_s,flow_mm3_s\n0,5\n1.0,10\n2.5,6\n4.0,11\n5.5,5\n")
        self.write("profile_speed.csv", "time_s,filament_speed_mm_s\n0,1\n1,2\n1,3\n2.5,1.5\n"
                   "4,3.5\n")
        # A width that follows the first-order lag (K 0.2 s) of profile.csv, 25 frames/s.
        knots = [(0, 5), (1.0, 10), (2.5, 6), (4.0, 11), (5.5, 5)]
        rows, y, t_prev = [], 5.0, 0.0
        for i in range(175):
            t = 0.02 + i / 25
            q = [f for (k, f) in knots if k <= t][-1]
            y = q + (y - q) * math.exp(-(t - t_prev) / 0.2)
            t_prev = t
            rows.append(f"lag.avi,{i},{t:.3f},1,{40 * y / 3:.3f},{40 * y:.3f}\n")
        self.write("lag_frames.csv", "source,frame,time_s,valid,width_px,width_um\n" + "".join(rows))
        self.sh("measure", "step1.mp4", "--scale-um-per-px", "10", "--out-frames",
                "measured_frames.csv")
        self.write("drive.csv", "step,temperature_c,mean_um,slip_pct\n1,220,400.0,\n"
                   "2,210,396.9,0.9\n3,200,390.1,\n4,190,381.3,1.5\n")
        feed = ["--no-nozzle", "--scale-um-per-px", "20", "--size", "320x240", "--tip-x-px",
                "160", "--tip-y-px", "0", "--fps", "30", "--frames", "8", "--surface-texture", "8",
                "--strand-width-um", "1750", "--feed-speed-mm-s", "4.5", "--drive-gear",
                "88,120,50", "--gear-surface-speed-mm-s", "5"]
        self.sh("render", "--out", "feed.avi", *feed)
        self.sh("render", "--out", "feed.mp4", *feed)
        block = ("feedstock:\n  scale_um_per_px: 20\n  gear_roi: 38,70,100,100\n"
                 "  gear_radius_mm: 1\n")
        self.write("feed.yaml", f"""name: feed
samples: 3
scale_um_per_px: 10
extruder: direct-pla
{block}steps:
  - {{step: 1, temperature_c: 220, video: {self.root}/step1.mp4, feedstock_video: {self.root}/feed.avi}}
  - {{step: 2, temperature_c: 210, video: {self.root}/step2.avi, feedstock_video: {self.root}/feed.mp4}}
""")
        self.write("feed_steps.yaml", f"""name: feed2
samples: 2
scale_um_per_px: 10
feedstock:
  scale_um_per_px: 20
steps:
  - {{step: 1, temperature_c: 220, images: {self.root}/frames, feedstock_video: {self.root}/feed.avi}}
""")


def tiff16(w, h):
    """A little-endian 16-bit grey TIFF holding 12-bit data: a bright vertical strand."""
    pix = bytearray()
    for y in range(h):
        for x in range(w):
            v = 3800 if 60 <= x < 100 else 600
            pix += struct.pack("<H", v + (x * 7 + y * 13) % 50)
    entries = [(256, 3, 1, w), (257, 3, 1, h), (258, 3, 1, 16), (259, 3, 1, 1), (262, 3, 1, 1),
               (273, 4, 1, 0), (277, 3, 1, 1), (278, 3, 1, h), (279, 4, 1, len(pix))]
    ifd_size = 2 + 12 * len(entries) + 4
    data_off = 8 + ifd_size
    out = bytearray(b"II*\x00" + struct.pack("<I", 8) + struct.pack("<H", len(entries)))
    for tag, typ, cnt, val in entries:
        if tag == 273:
            val = data_off
        out += struct.pack("<HHI", tag, typ, cnt)
        out += struct.pack("<HH", val, 0) if typ == 3 else struct.pack("<I", val)
    out += struct.pack("<I", 0) + pix
    return bytes(out)
