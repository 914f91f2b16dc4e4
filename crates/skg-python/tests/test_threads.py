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
    # A solve of a few hundred milliseconds (a global solve, then windows); on a machine
    # fast enough to finish it in under 0.2 s, a finer grid.
    for nodes in (2048, 8192, 32768):
        t0 = time.perf_counter()
        sol = skg.solve(scene("damped_oscillator"), nodes=nodes)
        t1 = time.perf_counter()
        if t1 - t0 > 0.2:
            break
    stop.set()
    th.join()
    assert sol.converged
    inside = [t for t in ticks if t0 < t < t1]
    duration = t1 - t0
    assert duration > 0.2, f"the solve took only {duration:.3f} s: too short to show anything"
    # Holding the GIL, the ticker could not run during the solve (at most a tick or two at
    # its edges); released, it ticks every few milliseconds, or less often when the machine
    # is loaded (two cores shared with the solve and other tests). Ten ticks tell the two
    # apart without asking the scheduler for a rate.
    assert len(inside) >= 10, f"{len(inside)} ticks in {duration:.3f} s"
