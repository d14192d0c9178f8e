"""One frame measured from 8 Python threads at once: the same result in every thread, and the
threads really inside the library together (the GIL released while measuring)."""

import threading

import numpy as np

import clogscope

THREADS = 8
ROUNDS = 4


def _fields(m):
    return (m.status, m.width_px, m.width_sigma_px, m.angle_deg, m.tip_x_px, m.tip_y_px,
            m.calipers_used, [c.width_px for c in m.calipers])


def test_eight_threads_measure_one_array_alike_and_at_once():
    images, _ = clogscope.render(clogscope.SceneParams(seed=31, highlight=True, tilt_deg=8))
    frame = images[0]
    reference = _fields(clogscope.measure_frame(frame))
    clogscope._core._peak_concurrent_measurements(reset=True)
    barrier = threading.Barrier(THREADS)
    results = [[] for _ in range(THREADS)]
    errors = []

    def work(i):
        try:
            barrier.wait()  # all threads start measuring together
            for _ in range(ROUNDS):
                results[i].append(_fields(clogscope.measure_frame(frame)))
        except Exception as e:  # reported below, not lost in the thread
            errors.append(e)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(THREADS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert all(r == [reference] * ROUNDS for r in results)
    # Held GIL: never more than one thread inside the library. Released: 8 threads × 4 frames
    # overlap (the counter is raised and lowered inside the call, without the GIL).
    assert clogscope._core._peak_concurrent_measurements() > 1


def test_trackers_in_threads_each_follow_their_own_video():
    scene = clogscope.SceneParams(width_jitter_um=2, seed=32)
    images, truth = clogscope.render(scene, frames=5)
    expected = [clogscope.Tracker().measure(f).width_px for f in images[:1]]
    results = {}
    barrier = threading.Barrier(4)

    def work(i):
        barrier.wait()
        tracker = clogscope.Tracker()
        results[i] = [tracker.measure(f).width_px for f in images]

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(results) == 4
    assert all(r == results[0] for r in results.values())
    assert results[0][0] == expected[0]
    assert np.max(np.abs(np.array(results[0]) - truth["width_px"].to_numpy())) < 0.1
