"""The examples of python/examples run, and say what they should."""
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import ROOT

EXAMPLES = ROOT / "python" / "examples"


def run(script: str, tmp_path: Path, *args: str) -> str:
    out = subprocess.run([sys.executable, str(EXAMPLES / script), *args], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_test3_example(tmp_path):
    text = run("test3.py", tmp_path)
    # the numbers of replication/results/test3.csv for mesh test3_1
    assert "  -20  hmm         5     735  0.8587899642" in text
    assert "   -5  hmm         8     295  0.3374031738" in text
    assert (tmp_path / "test3_p1_C20.vtu").is_file()


def test_gmsh_signorini_example(tmp_path):
    text = run("gmsh_signorini.py", tmp_path, str(tmp_path))
    assert "hmm: NITER" in text and "p1: NITER" in text
    png = tmp_path / "gmsh_signorini.png"
    assert png.is_file() and png.stat().st_size > 10_000
