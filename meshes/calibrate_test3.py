#!/usr/bin/env python3
"""Calibrate the characteristic length of the Test 3 meshes.

The paper's Test 3 meshes come from MATLAB's initmesh (Hmax = h) and have
872, 1342, 5422, 14006 triangles for h = 0.062, 0.050, 0.025, 0.016.  gmsh's
lc is not the same quantity, so for each target we scan lc = f*h on a grid of
factors f and keep the lc whose triangle count is closest to the target.
The chosen values are then written by hand into test3_k.geo (this script
only prints them; generate.sh does not run it).

Usage: python3 meshes/calibrate_test3.py   (needs the gmsh executable)
"""
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mesh_stats import stats  # noqa: E402

GEO = """DefineConstant[ lc = 0.05 ];
Mesh.MshFileVersion = 4.1; Mesh.Binary = 0;
General.NumThreads = 1; Mesh.Algorithm = 6;
Point(1) = {0, 0, 0, lc}; Point(2) = {1, 0, 0, lc};
Point(3) = {1, 1, 0, lc}; Point(4) = {0, 1, 0, lc};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Physical Curve("Gamma1", 1) = {1, 2, 3, 4}; Physical Surface("Omega", 10) = {1};
"""

TARGETS = [(0.062, 872), (0.050, 1342), (0.025, 5422), (0.016, 14006)]


def count(lc, d):
    geo = os.path.join(d, "c.geo")
    msh = os.path.join(d, "c.msh")
    with open(geo, "w") as fh:
        fh.write(GEO)
    subprocess.run(["gmsh", "-2", "-nt", "1", "-setnumber", "lc", repr(lc), geo, "-o", msh],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return stats(msh)


def main():
    with tempfile.TemporaryDirectory() as d:
        for h, target in TARGETS:
            best = None
            for i in range(0, 41):
                f = 0.78 + 0.0025 * i
                lc = round(h * f, 5)
                s = count(lc, d)
                err = abs(s["cells"] - target) / target
                if best is None or err < best[0]:
                    best = (err, lc, s)
            err, lc, s = best
            print(f"h={h:<6} target={target:<6} lc={lc:<8} cells={s['cells']:<6} "
                  f"({100 * (s['cells'] - target) / target:+.2f}%) max diam={s['hmax']:.5f}")


if __name__ == "__main__":
    main()
