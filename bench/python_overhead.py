#!/usr/bin/env python3
"""What measure_frame costs from Python against the C++ call it makes (issue 25: ≤ 1.1×).

A rendered 1280×720 grey reference frame is measured N times through clogscope.measure_frame
(timed in Python: argument conversion, the array view, GIL release, the result object) and N
times by vision::MeasureStrand in a C++ loop inside the same extension (_time_measure_strand),
in alternating rounds; the ratio of the medians is the overhead. Run on an idle machine:

    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [ROUNDS] [N]
"""

import statistics
import sys
import time

import clogscope


def main():
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 9
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 40
    images, _ = clogscope.render(clogscope.SceneParams(seed=1))
    frame = images[0]
    assert clogscope.measure_frame(frame).valid
    clogscope._core._time_measure_strand(frame, repeats=5)  # warm up
    py, cpp = [], []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(n):
            clogscope.measure_frame(frame)
        py.append((time.perf_counter() - t0) / n)
        cpp.append(clogscope._core._time_measure_strand(frame, repeats=n) / n)
    mp, mc = statistics.median(py), statistics.median(cpp)
    print("## measure_frame from Python against the C++ call (1280x720 grey, one thread)\n")
    print("| | ms/frame (median of {} rounds of {}) |".format(rounds, n))
    print("|---|---|")
    print(f"| vision::MeasureStrand, C++ loop | {1e3 * mc:.3f} |")
    print(f"| clogscope.measure_frame, Python loop | {1e3 * mp:.3f} |")
    print(f"\nPython / C++: **{mp / mc:.3f}×** (overhead {1e6 * (mp - mc):+.1f} µs per frame)")


if __name__ == "__main__":
    main()
