"""Ctrl-C during a long gradvi.solve: KeyboardInterrupt, promptly (the solve runs without the
GIL and checks Python's pending signals between linear solves)."""
import signal
import subprocess
import sys
import time

CHILD = """
import gradvi
mesh = gradvi.Mesh.generate("cartesian", 8)
pb = gradvi.Problem.builtin("test3")
print("solving", flush=True)
gradvi.solve(mesh, pb, warm_start="cold")
print("finished", flush=True)
"""


def test_sigint_raises_keyboard_interrupt_during_a_solve(tmp_path):
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline().strip() == "solving"
        time.sleep(1.0)  # into the active-set iteration (the cold start takes many solves)
        assert child.poll() is None, "the solve ended before it could be interrupted"
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=60)
        waited = time.monotonic() - sent
    finally:
        child.kill()
    assert "KeyboardInterrupt" in err, err
    assert "finished" not in out
    assert child.returncode != 0
    # one linear solve at most after the signal, not the rest of the iteration
    assert waited < 20, waited
