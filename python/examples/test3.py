"""The paper's Test 3 (obstacle problem) from Python: −Δu ≥ C, u ≥ ψ, (Δu + C)(ψ − u) = 0 in
(0,1)², u = 0 on ∂Ω, ψ = −min(x, 1 − x, y, 1 − y); NITER and the contact area for the four
values of C, with HMM and P1 on the gmsh mesh test3_1 (compare replication/results/test3.csv)."""
from pathlib import Path

import numpy as np

import gradvi

root = Path(__file__).resolve().parents[2]
mesh = gradvi.Mesh.read(root / "meshes" / "test3_1.msh")


def psi(x, y):  # the obstacle, vectorised: called once on the arrays of all the points
    return -np.minimum.reduce([x, 1 - x, y, 1 - y])


print("    C  scheme  NITER  active  contact area  certificate")
for c in (-5.0, -10.0, -15.0, -20.0):
    problem = gradvi.Problem(source=c, obstacle=psi, side="lower", name=f"test3 C={c:g}")
    for scheme in ("hmm", "p1"):
        sol = gradvi.solve(mesh, problem, scheme=scheme, warm_start="cold")  # the paper's NITER
        print(f"{c:5.0f}  {scheme:6}  {sol.niter:5d}  {sol.n_active:6d}  {sol.contact_measure:.10f}  {sol.certificate.worst():.1e}")
sol.write_vtu("test3_p1_C20.vtu")  # u, the active set and the multiplier, for ParaView
