#!/usr/bin/env python3
"""A mutation campaign over the whole `clogscope` command line (issue 12's acceptance check).

libFuzzer (`make fuzz`) drives each parser in-process; this drives the real binary, as a user's
files reach it: every input kind (manifests YAML/CSV, pins CSV, calibration YAML, diameter tables,
fit CSVs, temperature logs, extruder YAML, step JSON under --resume, images, micrometer images,
videos, command-line numbers, file-system paths; and the newer surfaces: lag frames and profiles,
thermal and drive tables, manifests with a feedstock block, filament speed with its gear, inspect,
watch on video files and on a folder that mutated, half-written, junk and future-stamped images
arrive in) is mutated from seeds the tool made itself, and each run is classified:
  crash     killed by a signal, or exit 134/136/139, or a sanitizer report in the output
  hang      still running after --timeout seconds (default 10)
  library   a line of library text (OpenCV, libpng, FFmpeg, glog, C++ runtime, ...) in the output
  clean     anything else (a result, or the tool's own one-line error)
Use the sanitizer build (build-asan/bin/clogscope) to catch memory errors. Findings are kept in
OUT/findings/<class>/<n>/ with the input, the command line and the output.

Seeds: fuzz/campaign_seeds.py. Usage: fuzz/campaign.py --bin build-asan/bin/clogscope --runs 10000 --jobs 2
(--kinds newer: only the newer surfaces; --kinds lag_frames,watch_folder: those.)
"""
import argparse
import collections
import concurrent.futures
import json
import os
import random
import re
import shutil
import signal
import struct
import subprocess
import sys
import time

# Text that only a library (never the tool's own messages) prints.
LIBRARY_TEXT = re.compile(
    r"OpenCV\(|cv::|\(-\d+:|terminate called|what\(\): |libpng|Corrupt JPEG|Premature end of JPEG"
    r"|JPEG datastream|TIFFRead|TIFFFetch|TIFF directory|\[[\w/.-]+ @ 0x|^ERROR \d+: "
    r"|basic_string|std::|filesystem error|Assertion .* failed|^[IWEF]\d{4} \d\d:"
    r"|WARNING: Logging before|yaml-cpp|\[json\.exception|moov atom"
    r"|^gnuplot|line \d+: |^\s*\^\s*$|GStreamer|gst_|VIDEOIO|Segmentation fault",
    re.M)
SANITIZER = re.compile(r"AddressSanitizer|LeakSanitizer|UndefinedBehaviorSanitizer|runtime error: ")

from campaign_seeds import Seeds  # noqa: E402  (next to this script)

INTERESTING_TOKENS = [
    b"inf", b"-inf", b"nan", b"NaN", b"1e309", b"-1e309", b"4.9e-324", b"1e308", b"-1", b"0",
    b"-0", b"2147483648", b"-2147483649", b"99999999999999999999", b"0x10", b"1,5", b"", b"\x00",
    b"\xff\xfe", b"\n", b",", b",,,,,,", b'"', b"'", b":", b"- ", b"[", b"{", b"[" * 2000,
    b"{a: " * 500, b"&a", b"*a", b"!!binary", b"~", b"null", b"true", b"A" * 5000,
]


def mutate(data: bytes, rng: random.Random, others: list) -> bytes:
    """One to four stacked mutations of the kinds libFuzzer uses, plus tokens and splices."""
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        op = rng.randrange(9)
        pos = rng.randrange(len(b) + 1)
        if op == 0 and b:  # flip bits
            for _ in range(rng.randint(1, 8)):
                i = rng.randrange(len(b))
                b[i] ^= 1 << rng.randrange(8)
        elif op == 1 and b:  # random bytes
            for _ in range(rng.randint(1, 16)):
                b[rng.randrange(len(b))] = rng.randrange(256)
        elif op == 2:  # a token in place of a word or number
            tok = rng.choice(INTERESTING_TOKENS)
            m = list(re.finditer(rb"[-+]?[0-9][0-9.eE+-]*|[A-Za-z_]+", bytes(b)))
            if m and rng.random() < 0.7:
                w = rng.choice(m)
                b[w.start():w.end()] = tok
            else:
                b[pos:pos] = tok
        elif op == 3 and b:  # delete a range
            n = rng.randint(1, max(1, len(b) // rng.choice([2, 8, 64])))
            del b[pos:pos + n]
        elif op == 4 and b:  # duplicate a range
            a = rng.randrange(len(b))
            n = rng.randint(1, max(1, min(len(b) - a, 4096)))
            b[pos:pos] = b[a:a + n] * rng.randint(1, 8)
        elif op == 5:  # truncate
            del b[pos:]
        elif op == 6 and others:  # splice another seed of the same kind
            o = rng.choice(others)
            if o:
                a = rng.randrange(len(o))
                b[pos:] = o[a:]
        elif op == 7 and len(b) >= 4:  # a binary integer field
            i = rng.randrange(len(b) - 3)
            b[i:i + 4] = struct.pack("<I", rng.choice([0, 1, 0x7FFFFFFF, 0xFFFFFFFF, 0x10000,
                                                        rng.randrange(1 << 32)]))
        elif op == 8 and b:  # swap lines
            lines = bytes(b).split(b"\n")
            if len(lines) > 2:
                i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
                lines[i], lines[j] = lines[j], lines[i]
                b = bytearray(b"\n".join(lines))
    return bytes(b)


# The tool's own lines: "clogscope CMD: error: …", "[level] …", progress bars. A library's reason
# quoted inside one of them ("cannot decode image (libpng: …)") is the tool's message.
TOOL_LINE = re.compile(r"^(clogscope[ :]|\[(trace|debug|info|warning|error|critical)\] |\r?\[#*-*\] )")


def library_lines(text):
    return [l for l in text.splitlines() if LIBRARY_TEXT.search(l) and not TOOL_LINE.match(l)]


def run(cmd, cwd, timeout_s, during=None):
    """Runs a command in its own process group; `during`, when given, runs beside it (writes
    files into a watched folder). Returns (status, rc, output, seconds)."""
    env = dict(os.environ)
    env["ASAN_OPTIONS"] = "detect_leaks=1:abort_on_error=0:allocator_may_return_null=1"
    env["UBSAN_OPTIONS"] = "print_stacktrace=1:halt_on_error=1"
    env.pop("CLOGSCOPE_LOG", None)
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         stdin=subprocess.DEVNULL, env=env, start_new_session=True)
    if during:
        during()
    try:
        out, _ = p.communicate(timeout=max(0.1, timeout_s - (time.monotonic() - t0)))
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, _ = p.communicate()
        return "hang", None, out.decode("utf-8", "replace"), time.monotonic() - t0
    text = out.decode("utf-8", "replace")
    rc = p.returncode
    if rc < 0 or rc in (134, 136, 139) or SANITIZER.search(text):
        status = "crash"
    elif library_lines(text):
        status = "library"
    else:
        status = "clean"
    return status, rc, text, time.monotonic() - t0


def build_case(kind, seeds, rng, work):
    """Writes the mutated input into `work` and returns the command that reads it."""
    b = seeds.bin
    r = seeds.root
    files = seeds.files.get(kind, [])

    def mutated(ext, src=None):
        src = src or rng.choice(files)
        data = open(src, "rb").read()
        others = [open(f, "rb").read() for f in files if f != src]
        path = os.path.join(work, "input" + ext)
        with open(path, "wb") as f:
            f.write(mutate(data, rng, others))
        return path, src
    mutated.files = files
    mutated.work = os.path.join(work, "input")

    if kind == "manifest_yaml":
        p, _ = mutated(".yaml")
        return [b, "run", p, "--out", "out", "--jobs", "1"]
    if kind == "manifest_csv":
        p, _ = mutated(".csv")
        return [b, "run", p, "--out", "out", "--scale-um-per-px", "10", "--samples", "3"]
    if kind == "temperature_log":
        p, _ = mutated(".csv")
        m = open(os.path.join(r, "logged.yaml")).read().replace(f"{r}/temps.csv", p)
        open(os.path.join(work, "m.yaml"), "w").write(m)
        return [b, "run", "m.yaml", "--out", "out"]
    if kind == "pins_csv":
        p, _ = mutated(".csv")
        return [b, "calibrate", "--pins", p, "--out", "c.yaml"]
    if kind == "calibration_yaml":
        p, _ = mutated(".yaml")
        if rng.random() < 0.5:
            return [b, "measure", f"{r}/frames", "--calib", p, "--out-frames", "f.csv"]
        m = open(os.path.join(r, "experiment.yaml")).read().replace(f"{r}/calib.yaml", p)
        open(os.path.join(work, "m.yaml"), "w").write(m)
        return [b, "run", "m.yaml", "--out", "out", "--jobs", "1"]
    if kind == "diameters_csv":
        p, _ = mutated(".csv")
        return [b, "predict", "--diameters", p, "--out", "p"] + (
            ["--no-plots"] if rng.random() < 0.8 else [])
    if kind == "fit_csv":
        p, _ = mutated(".csv")
        params = rng.choice(["gain_m_s2_per_n", "activation_temperature_k,gain_m_s2_per_n",
                             "current_gain_ma_per_n,current_offset_ma"])
        return [b, "predict", "--diameters", f"{r}/runout/diameters.csv", "--fit", p,
                "--fit-params", params, "--out", "p", "--no-plots"]
    if kind == "extruder_yaml":
        p, _ = mutated(".yaml")
        return [b, "predict", "--extruder", p, "--diameters", f"{r}/runout/diameters.csv",
                "--out", "p", "--no-plots"]
    if kind == "step_json":
        shutil.copytree(os.path.join(r, "runout"), os.path.join(work, "out"))
        src = rng.choice(files)
        dst = os.path.join(work, "out", "steps", os.path.basename(src))
        data = open(src, "rb").read()
        open(dst, "wb").write(mutate(data, rng, [open(f, "rb").read() for f in files]))
        return [b, "run", f"{r}/experiment.yaml", "--out", "out", "--resume", "--jobs", "1"]
    if kind == "image":
        src = rng.choice(files)
        p, _ = mutated(os.path.splitext(src)[1] if rng.random() < 0.9 else ".png")
        if rng.random() < 0.3:
            return [b, "inspect", p, "--out", "i.png"]
        return [b, "measure", p, "--out-frames", "f.csv", "--overlay", "ov"]
    if kind == "micrometer_image":
        p, _ = mutated(".png")
        return [b, "calibrate", "--micrometer", p, "--pitch-um", "100", "--out", "c.yaml"]
    if kind == "video":
        src = rng.choice(files)
        p, _ = mutated(os.path.splitext(src)[1])
        if rng.random() < 0.2:
            return [b, "inspect", p, "--frame", str(rng.choice([0, 5, 11, 1000])), "--out", "i.png"]
        return [b, "measure", p, "--out-frames", "f.csv"]
    if kind in NEWER_KINDS:
        return newer_case(kind, b, r, rng, mutated)
    if kind == "numbers":
        return numbers_case(b, r, rng)
    if kind == "paths":
        return paths_case(b, r, rng, work)
    raise ValueError(kind)


def weird_option(rng, cmd, opts):
    """Sets one of `opts` to an odd number (or leaves the command as it is, half the time)."""
    if rng.random() < 0.5:
        opt = rng.choice(opts)
        v = rng.choice(WEIRD_NUMBERS)
        if opt in cmd:
            cmd[cmd.index(opt) + 1] = v
        else:
            cmd += [opt, v]
    return cmd


def newer_case(kind, b, r, rng, mutated):
    """The newer surfaces: lag, thermal, drive, feedstock manifests, filament speed and gear,
    inspect, watch on files and folders."""
    if kind == "lag_frames":
        p, _ = mutated(".csv")
        cmd = [b, "lag", "--frames", p, "--commanded", f"{r}/profile.csv", "--out", "o",
               "--no-plots"]
        return weird_option(rng, cmd, ["--max-offset-s", "--max-k-s", "--filament-diameter-mm"])
    if kind == "lag_profile":
        p, _ = mutated(".csv")
        form = ["--profile-form", rng.choice(["moves", "linear"])]
        c = rng.random()
        if c < 0.4:
            cmd = [b, "lag", "--frames", f"{r}/lag_frames.csv", "--commanded", p, "--out", "o",
                   "--no-plots", *form]
            return weird_option(rng, cmd, ["--max-offset-s", "--max-k-s"])
        if c < 0.8:
            cmd = [b, "lag", "--commanded", p, "--k-s", "0.2", "--dt-s", "0.01", "--out", "o",
                   "--no-plots", *form]
            return weird_option(rng, cmd, ["--k-s", "--k-la-s", "--dt-s",
                                           "--filament-diameter-mm"])
        return [b, "render", "--out", "r", "--frames", "3", "--size", "160x120", "--tip-x-px",
                "80", "--tip-y-px", "30", "--lag-commanded", p, "--lag-k-s", "0.1"]
    if kind == "thermal":
        p, _ = mutated(".csv")
        cmd = [b, "thermal", "--material", rng.choice(["pla", "abs"]), "--fan-velocity-m-s",
               "0.3", "--diameters", p, "--filament-modulus-pa", "5e7", "--out", "t"]
        return weird_option(rng, cmd, ["--fan-velocity-m-s", "--t4-c", "--filament-modulus-pa",
                                       "--viscosity-pa-s", "--hp-length-mm"])
    if kind == "drive":
        p, _ = mutated(".csv")
        if rng.random() < 0.25:
            cmd = [b, "drive", "--roller", rng.choice(["1", "3", "7", "hobb-goblin"]),
                   "--pinch-force-n", "80", "--feed-force-n", "20"]
            return weird_option(rng, cmd, ["--pinch-force-n", "--feed-force-n",
                                           "--filament-speed-mm-s", "--friction-n",
                                           "--k-p-pct", "--roller"])
        cmd = [b, "drive", "--roller", "3", "--pinch-force-n", "80", "--diameters", p,
               "--out", "d"]
        return weird_option(rng, cmd, ["--pinch-force-n", "--friction-n", "--k-p-pct"])
    if kind == "feedstock_manifest":
        p, _ = mutated(".yaml")
        if rng.random() < 0.5:
            return [b, "run", p, "--out", "out", "--jobs", "1"]
        return [b, "measure", "--manifest", p, "--out", "out", "--jobs", "1"]
    if kind == "filament_speed":
        if rng.random() < 0.7:
            src = rng.choice(["feed.avi", "feed.mp4"])
            p, _ = mutated(os.path.splitext(src)[1])
        else:
            p = f"{r}/feed.avi"
        cmd = [b, "measure", p, "--target", "filament", "--speed", "--scale-um-per-px", "20",
               "--gear-roi", "38,70,100,100", "--gear-radius-mm", "1", "--out-frames", "f.csv"]
        if rng.random() < 0.3:
            v = [rng.choice(WEIRD_NUMBERS + ["10", "100", "5000"]) for _ in range(4)]
            cmd[cmd.index("--gear-roi") + 1] = ",".join(v)
        if rng.random() < 0.3:
            cmd += ["--gear-centre", ",".join(rng.choice(WEIRD_NUMBERS + ["88", "120"])
                                               for _ in range(rng.choice([2, 3])))]
        return weird_option(rng, cmd, ["--gear-radius-mm", "--scale-um-per-px"])
    if kind == "inspect":
        src = rng.choice(seeds_of(mutated))
        p, _ = mutated(os.path.splitext(src)[1], src)
        cmd = [b, "inspect", p, "--out", "i.png"]
        if rng.random() < 0.4:
            cmd += ["--target", rng.choice(["strand", "filament"])]
        return weird_option(rng, cmd, ["--frame", "--roi", "--band-start-px", "--band-height-px"])
    if kind == "watch_file":
        src = rng.choice(seeds_of(mutated))
        p, _ = mutated(os.path.splitext(src)[1], src)
        cmd = [b, "watch", p, "--scale-um-per-px", "10", "--duration-s", "5", "--report-s", "0.5"]
        if rng.random() < 0.3:
            cmd += ["--extruder", "direct-pla"]
        return cmd
    if kind == "watch_folder":
        os.makedirs(os.path.join(os.path.dirname(mutated.work), "cam"), exist_ok=True)
        cmd = [b, "watch", "cam", "--duration-s", "2.5", "--report-s", "0.5"]
        if rng.random() < 0.5:
            cmd += ["--scale-um-per-px", "10"]
        return cmd
    raise ValueError(kind)


def seeds_of(mutated):
    return mutated.files


def folder_writer(rng, seeds, work):
    """While `watch` runs on WORK/cam: mutated, half-written, junk, empty and future-stamped
    images arrive one after another, and one is replaced."""
    def write():
        cam = os.path.join(work, "cam")
        files = seeds.files["watch_folder"]
        datas = [open(f, "rb").read() for f in files]
        time.sleep(0.4)
        for i in range(rng.randint(2, 6)):
            src = rng.randrange(len(files))
            ext = os.path.splitext(files[src])[1] if rng.random() < 0.9 else ".png"
            path = os.path.join(cam, f"shot{i:03d}{ext}")
            data = mutate(datas[src], rng, datas) if rng.random() < 0.7 else datas[src]
            how = rng.random()
            if how < 0.15:  # half-written: the rest follows a little later
                cut = rng.randrange(len(data) + 1)
                with open(path, "wb") as f:
                    f.write(data[:cut])
                    f.flush()
                    time.sleep(rng.choice([0.05, 0.2, 0.5]))
                    f.write(data[cut:])
            elif how < 0.25:  # junk under an image name
                open(path, "wb").write(bytes(rng.randrange(256) for _ in range(rng.randrange(200))))
            elif how < 0.3:
                open(path, "wb").close()
            else:
                open(path, "wb").write(data)
            if rng.random() < 0.2:  # a camera whose clock is off
                t = time.time() + rng.choice([-86400.0, 86400.0, 3e8])
                os.utime(path, (t, t))
            if rng.random() < 0.1 and i > 0:  # one replaced in place
                open(os.path.join(cam, f"shot{i - 1:03d}{ext}"), "wb").write(data)
            time.sleep(rng.choice([0.0, 0.05, 0.15, 0.3]))
    return write


WEIRD_NUMBERS = ["inf", "-inf", "nan", "1e309", "-1e309", "4.9e-324", "1e308", "-1", "0", "-0",
                 "1e-300", "2147483648", "-2147483649", "99999999999999999999", "0x10", "1,5",
                 "", " ", "abc", "1e", "--", "3.0.0", "1e5", "65535", "-65536", "0.0001"]


def numbers_case(b, r, rng):
    """A command with one (or two) of its numeric options set to something odd."""
    cmds = [
        ([b, "render", "--out", "r", "--size", "160x120", "--tip-x-px", "80", "--tip-y-px", "30"],
         ["--frames", "--fps", "--scale-um-per-px", "--strand-width-um", "--tip-x-px",
          "--tip-y-px", "--tilt-deg", "--blur-px", "--noise", "--background", "--strand-level",
          "--gradient", "--sway-deg", "--width-jitter-um", "--edge-bias-px", "--pitch-um",
          "--line-width-um", "--bit-depth", "--seed", "--nozzle-level", "--texture", "--discs",
          "--gears", "--shading-ambient", "--vignetting", "--bed-gap-um", "--size",
          "--strand-tint", "--background-tint"]),
        ([b, "measure", f"{r}/frames", "--out-frames", "f.csv"],
         ["--scale-um-per-px", "--overlay-every", "--roi", "--band-start-um", "--band-height-um",
          "--band-start-px", "--band-height-px", "--caliper-px", "--max-blur-px",
          "--min-contrast"]),
        ([b, "measure", "--manifest", f"{r}/experiment.yaml", "--out", "out"],
         ["--samples", "--jobs", "--scale-um-per-px", "--band-start-px", "--roi"]),
        ([b, "calibrate", "--micrometer", f"{r}/micro/frame_000000.png", "--out", "c.yaml",
          "--pitch-um", "100"],
         ["--pitch-um", "--expect-scale-um-per-px", "--roi"]),
        ([b, "calibrate", "--pins", f"{r}/pins.csv", "--out", "c.yaml"], ["--roi"]),
        ([b, "predict", "--diameters", f"{r}/runout/diameters.csv", "--out", "p", "--no-plots"],
         ["--set"]),
        ([b, "run", f"{r}/experiment.yaml", "--out", "out"],
         ["--samples", "--jobs", "--scale-um-per-px"]),
        ([b, "inspect", f"{r}/step1.mp4", "--out", "i.png"],
         ["--frame", "--roi", "--band-start-px", "--band-height-px"]),
    ]
    base, opts = rng.choice(cmds)
    cmd = list(base)
    for _ in range(rng.randint(1, 2)):
        opt = rng.choice(opts)
        v = rng.choice(WEIRD_NUMBERS)
        if opt in ("--roi", "--size", "--strand-tint", "--background-tint"):
            parts = [rng.choice(WEIRD_NUMBERS + ["10", "100", "5000"]) for _ in range(
                rng.choice([2, 3, 4, 5]))]
            v = rng.choice([",", "x"]).join(parts)
        elif opt == "--set":
            name = rng.choice(["damping_ratio", "flow_index", "consistency_pa_sn",
                               "nozzle_diameter_m", "natural_frequency_hz", "load_model",
                               "activation_temperature_k", "nonsense"])
            v = f"{name}={v}"
        if opt in cmd:
            cmd[cmd.index(opt) + 1] = v
        else:
            cmd += [opt, v]
    return cmd


def paths_case(b, r, rng, work):
    """A command with one path argument replaced by an awkward file-system object."""
    os.makedirs(os.path.join(work, "adir"), exist_ok=True)
    loop = os.path.join(work, "loop")
    os.symlink(loop, loop)
    os.symlink("/nonexistent/target", os.path.join(work, "dangling"))
    os.mkfifo(os.path.join(work, "fifo"))
    open(os.path.join(work, "empty"), "wb").close()
    open(os.path.join(work, "afile"), "w").write("x\n")
    weird = [os.path.join(work, "adir"), loop, os.path.join(work, "dangling"),
             os.path.join(work, "fifo"), os.path.join(work, "empty"), "/dev/null", "/dev/zero",
             "/dev/full", "/proc/self/mem", "/", "", ".", "..", "-", "--help", "x" * 300,
             "/" + "d/" * 2100 + "f", "nl\nname.png", "sp ace.png", "\u00e9t\u00e9.png",
             os.path.join(work, "afile", "below.png"), "/nonexistent/dir/out.csv",
             os.path.join(work, "adir") + "/", "/proc", "/sys/kernel"]
    cmds = [
        [b, "measure", "@IN", "--out-frames", "@OUT"],
        [b, "measure", f"{r}/frames", "--out-frames", "@OUT", "--overlay", "@OUT"],
        [b, "measure", "--manifest", "@IN", "--out", "@OUT"],
        [b, "measure", f"{r}/frames", "--calib", "@IN", "--out-frames", "f.csv"],
        [b, "calibrate", "--pins", "@IN", "--out", "@OUT"],
        [b, "calibrate", "--micrometer", "@IN", "--pitch-um", "100", "--out", "@OUT"],
        [b, "calibrate", "--pins", f"{r}/pins.csv", "--out", "@OUT", "--plot", "@OUT"],
        [b, "predict", "--diameters", "@IN", "--out", "@OUT"],
        [b, "predict", "--extruder", "@IN", "--diameters", f"{r}/runout/diameters.csv",
         "--out", "@OUT", "--no-plots"],
        [b, "predict", "--diameters", f"{r}/runout/diameters.csv", "--fit", "@IN",
         "--out", "p", "--no-plots"],
        [b, "run", "@IN", "--out", "@OUT"],
        [b, "run", f"{r}/experiment.yaml", "--out", "@OUT", "--calib", "@IN"],
        [b, "render", "--out", "@OUT", "--size", "160x120", "--tip-x-px", "80"],
        [b, "render", "--out", "@OUT", "--truth", "@OUT", "--size", "160x120"],
        [b, "inspect", "@IN", "--out", "@OUT"],
    ]
    cmd = list(rng.choice(cmds))
    defaults = {"@IN": f"{r}/frames/frame_000000.png", "@OUT": "o"}
    slots = [i for i, a in enumerate(cmd) if a in defaults]
    pick = rng.choice(slots)
    for i in slots:
        cmd[i] = rng.choice(weird) if i == pick else defaults[cmd[i]]
    return cmd


NEWER_KINDS = ["lag_frames", "lag_profile", "thermal", "drive", "feedstock_manifest",
               "filament_speed", "inspect", "watch_file", "watch_folder"]
KINDS = ["manifest_yaml", "manifest_csv", "temperature_log", "pins_csv", "calibration_yaml",
         "diameters_csv", "fit_csv", "extruder_yaml", "step_json", "image", "micrometer_image",
         "video", "numbers", "paths"] + NEWER_KINDS


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", required=True, help="clogscope binary (the sanitizer build)")
    ap.add_argument("--runs", type=int, default=10000)
    ap.add_argument("--out", default="build-campaign")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=10.0)
    ap.add_argument("--jobs", type=int, default=os.cpu_count())
    ap.add_argument("--kinds", default="all",
                    help="comma-separated input kinds, 'newer' for the newer surfaces, or all")
    args = ap.parse_args()
    kinds = (KINDS if args.kinds == "all" else NEWER_KINDS if args.kinds == "newer"
             else args.kinds.split(","))
    for k in kinds:
        if k not in KINDS:
            sys.exit(f"unknown kind {k}: one of {', '.join(KINDS)}")
    seeds = Seeds(args.bin, os.path.join(args.out, "seeds"))
    print("making seeds with", args.bin, flush=True)
    seeds.make()
    counts = collections.defaultdict(collections.Counter)
    lib_lines = collections.Counter()
    findings = os.path.join(os.path.abspath(args.out), "findings")
    shutil.rmtree(findings, ignore_errors=True)
    t_start = time.monotonic()
    slowest = (0.0, None)
    exits = collections.Counter()  # 0 done, 1 refused with a message, 2 partly done, …

    def one(n):
        # Each case from its own generator: the same seed gives the same cases at any --jobs.
        rng = random.Random(f"{args.seed}-{n}")
        kind = kinds[n % len(kinds)]
        work = os.path.join(os.path.abspath(args.out), "work", str(n))
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
        cmd = build_case(kind, seeds, rng, work)
        during = folder_writer(rng, seeds, work) if kind == "watch_folder" else None
        status, rc, out, secs = run(cmd, work, args.timeout, during)
        kept = None
        if status != "clean":
            kept = os.path.join(findings, status, f"{n:05d}_{kind}")
            os.makedirs(kept)
            for f in os.listdir(work):
                p = os.path.join(work, f)
                if f.startswith("input") and os.path.isfile(p):
                    shutil.copy(p, kept)
                if f == "cam" and os.path.isdir(p):
                    shutil.copytree(p, os.path.join(kept, "cam"))
            open(os.path.join(kept, "command"), "w").write(
                " ".join(a if re.fullmatch(r"[\w./,=:@-]+", a) else repr(a) for a in cmd)
                + f"\nexit {rc}\n")
            open(os.path.join(kept, "output"), "w").write(out)
        shutil.rmtree(work, ignore_errors=True)
        return kind, status, out, secs, cmd, rc

    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for n, (kind, status, out, secs, cmd, rc) in enumerate(pool.map(one, range(args.runs))):
            exits[str(rc)] += 1
            if secs > slowest[0]:
                slowest = (secs, cmd)
            counts[kind][status] += 1
            for line in library_lines(out) if status == "library" else []:
                lib_lines[re.sub(r"0x[0-9a-f]+|\d+", "N", line.strip())[:160]] += 1
            if (n + 1) % 250 == 0:
                total = collections.Counter()
                for c in counts.values():
                    total.update(c)
                print(f"{n + 1} runs, {time.monotonic() - t_start:.0f} s: {dict(total)}",
                      flush=True)
    total = collections.Counter()
    for c in counts.values():
        total.update(c)
    report = {
        "runs": args.runs,
        "kinds": kinds,
        "seconds": round(time.monotonic() - t_start),
        "binary": args.bin,
        "totals": dict(total),
        "library_text_pct": round(100.0 * total["library"] / max(1, args.runs), 3),
        "exit_codes": dict(exits.most_common()),
        "by_kind": {k: dict(v) for k, v in counts.items()},
        "library_lines": lib_lines.most_common(40),
        "slowest_s": round(slowest[0], 2),
        "slowest_command": slowest[1],
    }
    json.dump(report, open(os.path.join(args.out, "report.json"), "w"), indent=1)
    print(json.dumps(report, indent=1))
    return 1 if total["crash"] or total["hang"] else 0


if __name__ == "__main__":
    sys.exit(main())
