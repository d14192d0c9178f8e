"""Seeds for fuzz/campaign.py: one small input of every kind, made by `clogscope` itself (renders,
a calibration, a finished run with its step files) plus a JPEG cut from the MJPEG video and a
16-bit TIFF written here."""
import json
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
        }
        for k, names in kinds.items():
            self.files[k] = [os.path.join(self.root, n) for n in names]
        json.dump(self.files, open(os.path.join(self.root, "seeds.json"), "w"), indent=1)


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
