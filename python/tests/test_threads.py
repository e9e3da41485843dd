"""The GIL is released while Rust works; Ctrl-C cancels; threads share a volume."""

import _thread
import signal
import threading
import time

import numpy as np
import pytest
import voxless


@pytest.fixture(scope="module")
def big():
    rng = np.random.default_rng(2)
    return voxless.Particles(rng.random((200_000, 3)), radius=0.02)


def test_a_python_thread_runs_during_a_render(big):
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    time.sleep(0.01)
    start = time.perf_counter()
    big.render(size=(320, 240), spp=2)
    end = time.perf_counter()
    stop.set()
    t.join()
    during = [x for x in ticks if start < x < end]
    # The thread ran all along (it would not run at all if the GIL were held).
    assert end - start > 0.05
    assert len(during) >= 10, f"{len(during)} ticks in {end - start:.3f}s"


def test_ctrl_c_cancels_a_render(big):
    # A process started in the background of a non-interactive shell
    # inherits SIGINT ignored, and `interrupt_main` then does nothing: the
    # render would run to its end (many minutes). Python's own handler is
    # installed for the test, as an interactive session has it.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _ctrl_c_cancels(big)
    finally:
        signal.signal(signal.SIGINT, previous)


def _ctrl_c_cancels(big):
    timer = threading.Timer(0.2, _thread.interrupt_main)
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        big.render(size=(2048, 2048), spp=64)
    elapsed = time.perf_counter() - start
    timer.cancel()
    assert elapsed < 10.0, f"the render ran {elapsed:.1f}s after Ctrl-C"
    # The volume still works.
    assert big.render(size=(16, 16)).shape == (16, 16, 4)


def test_threads_render_one_volume_at_once(big):
    expected = big.render(size=(64, 48), colormap="magma")
    results = [None] * 4

    def work(i):
        results[i] = big.render(size=(64, 48), colormap="magma")

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        np.testing.assert_array_equal(r, expected)
