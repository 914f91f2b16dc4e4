"""The GIL is released during a solve: another Python thread runs meanwhile."""

import threading
import time

import skg


def test_another_thread_progresses_during_a_solve(scene):
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.002)

    th = threading.Thread(target=ticker)
    th.start()
    time.sleep(0.05)
    # A solve of a few hundred milliseconds (a global solve, then windows).
    t0 = time.perf_counter()
    sol = skg.solve(scene("damped_oscillator"), nodes=2048)
    t1 = time.perf_counter()
    stop.set()
    th.join()
    assert sol.converged
    inside = [t for t in ticks if t0 < t < t1]
    duration = t1 - t0
    assert duration > 0.2, f"the solve took only {duration:.3f} s: too short to show anything"
    # Holding the GIL, the ticker could not run during the solve (at most a tick or two at its
    # edges); released, it ticks every few milliseconds. Ask for a quarter of the ideal rate.
    assert len(inside) > 0.25 * duration / 0.002, f"{len(inside)} ticks in {duration:.3f} s"
