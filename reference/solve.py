#!/usr/bin/python3
"""P1 (dolfinx 0.5) reference solutions of the Alnashri & Droniou test cases.

Run with Debian's /usr/bin/python3 (python3-dolfinx 0.5.2), not a pyenv python.

  /usr/bin/python3 reference/solve.py --case test3_2_C10 --mesh meshes/test3_2.msh --outdir DIR
  /usr/bin/python3 reference/solve.py --coarse --outdir DIR   # coarsest mesh of each test
  /usr/bin/python3 reference/solve.py --all --outdir DIR      # every case on every mesh

Cases (k = 1..4 is the mesh index, meshes/<test>_<k>.msh):
  test1_k        Signorini, -Lap u = 2 pi sin(2 pi x); u = 0 on Gamma1 (y=1),
                 grad u.n = 0 on Gamma2 (x=0, x=1), u >= 0 / grad u.n >= 0 /
                 u grad u.n = 0 on Gamma3 (y=0)          -> lower bound 0 on Gamma3 dofs
  test2tri_k     heterogeneous Signorini, -div(A grad u) = f, A = 100 I (y<1/2), I (y>1/2)
                 as DG0 (value at the centroid); u = 0 on Gamma1 (y=0, y=1),
                 A grad u.n = 0 on Gamma2 (x=1), u <= 0 / A grad u.n <= 0 /
                 u A grad u.n = 0 on Gamma3 (x=0)        -> upper bound 0 on Gamma3 dofs
  test3_k_C<c>   obstacle, -Lap u >= C, u >= psi, (-Lap u - C)(u - psi) = 0,
                 u = 0 on the boundary, psi = -min(x, 1-x, y, 1-y), C = -c, c in {5,10,15,20}
                                                          -> lower bound psi on every dof

Discretisation: P1 ("CG", 1). The load is int f_h v dx with f_h the P1 interpolant of f
(nodal values f(x_v)); ufl's default quadrature degree for f_h*v is 2, exact for this
product, so the load equals M @ f(x_v) with M the P1 mass matrix. Dirichlet dofs (dofs on
facets tagged 1) get identity rows in the matrix, value 0 in the right-hand side, and
bounds lb = ub = 0. The discrete VI "find u in K: a(u, v - u) >= L(v - u)" is solved as
the bound-constrained complementarity problem for F(u) = A u - b with PETSc SNES
"vinewtonrsls" (reduced-space active set Newton; basic line search, LU on the reduced
system), initial guess u0 = 0 projected onto [lb, ub] (= 0 in all cases, since every lower
bound is <= 0 and every upper bound is >= 0).

Outputs (CSV schema read by the Rust side):
  <outdir>/nodal_<case>.csv          x,y,u  one row per vertex, in gmsh node-tag order, %.17g
  <outdir>/reference_summary.csv     one row per case (rows of re-run cases are replaced)
"""
import argparse
import csv
import math
import os
import re
import sys
import time

import numpy as np

import logging

logging.disable(logging.INFO)  # silence the ffcx/cffi JIT "INFO:root:" lines

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MESHDIR = os.path.join(ROOT, "meshes")

SUMMARY_HEADER = ["case", "test", "mesh", "C", "n_cells", "n_vertices", "n_constrained",
                  "snes_iterations", "snes_reason", "time_setup_s", "time_solve_s",
                  "min_bound_gap", "residual_inf"]

C_VALUES = [5, 10, 15, 20]
ALL_CASES = ([f"test1_{k}" for k in range(1, 5)]
             + [f"test2tri_{k}" for k in range(1, 5)]
             + [f"test3_{k}_C{c}" for k in range(1, 5) for c in C_VALUES])
COARSE_CASES = ["test1_1", "test2tri_1"] + [f"test3_1_C{c}" for c in C_VALUES]
# 3D cases (tetrahedra): the 3D radial obstacle of problems/ex9-3d.toml on meshes/3d/ex9_3d_k.msh
# and the 3D Signorini problem of problems/signorini-3d.toml on meshes/3d/signorini3d_k.msh
ALL_CASES_3D = ["ex9_3d_1", "ex9_3d_2", "signorini3d_1", "signorini3d_2"]
COARSE_CASES_3D = ["ex9_3d_1", "signorini3d_1"]
TESTS_3D = {"ex9_3d": "ex9-3d", "signorini3d": "signorini-3d"}
SUMMARY_3D = "reference_summary_3d.csv"

CASE_RE = re.compile(r"^(test1|test2tri|test3|ex9_3d|signorini3d)_([1-9][0-9]*)(?:_C([0-9]+))?$")


def log(msg):
    print(f"[solve.py] {msg}", file=sys.stderr, flush=True)


def parse_case(case):
    m = CASE_RE.match(case)
    if not m:
        raise SystemExit(f"solve.py: bad case name '{case}' (expected test1_K, test2tri_K, test3_K_C<abs C> "
                         "ex9_3d_K or signorini3d_K)")
    test, k, c = m.group(1), int(m.group(2)), m.group(3)
    if test == "test3" and c is None:
        raise SystemExit(f"solve.py: case '{case}': test3 needs _C<abs C>, e.g. test3_{k}_C10")
    if test != "test3" and c is not None:
        raise SystemExit(f"solve.py: case '{case}': only test3 takes a C")
    return test, k, (-float(c) if c is not None else None)


# ---------------------------------------------------------------------------
# Data of the three tests (vectorised over x = array of shape (3, n))

def f_test1(x):
    return 2.0 * np.pi * np.sin(2.0 * np.pi * x[0])


def P2(y):
    return -y * (y - 0.5) ** 2


def G2(y):
    return (1.0 - y) * (y - 0.5) ** 2


def f2_lower(x):  # y < 1/2, A = 100 I, u = P(y) cos(pi x)
    return 100.0 * np.cos(np.pi * x[0]) * (np.pi ** 2 * P2(x[1]) - 2.0 + 6.0 * x[1])


def f2_upper(x):  # y > 1/2, A = I, u = sin^2(pi x / 2) G(y)
    return -((np.pi ** 2 / 2.0) * np.cos(np.pi * x[0]) * G2(x[1])
             + np.sin(np.pi * x[0] / 2.0) ** 2 * (4.0 - 6.0 * x[1]))


INTERFACE_TOL = 1e-12


def f_test2(x):
    """f for Test 2; f jumps across y = 1/2 (100 cos(pi x) below, -sin^2(pi x/2) above),
    so vertices on the interface get the average of the two one-sided values."""
    lo, up = f2_lower(x), f2_upper(x)
    on = np.abs(x[1] - 0.5) <= INTERFACE_TOL
    return np.where(on, 0.5 * (lo + up), np.where(x[1] < 0.5, lo, up))


def u_exact_test2(x):
    return np.where(x[1] < 0.5, P2(x[1]) * np.cos(np.pi * x[0]),
                    np.sin(np.pi * x[0] / 2.0) ** 2 * G2(x[1]))


def A_test2(x):
    """Scalar diffusion coefficient (A = a I) at the interpolation point of DG0 = centroid."""
    return np.where(x[1] < 0.5, 100.0, 1.0)


def psi_test3(x):
    return -np.minimum(np.minimum(x[0], 1.0 - x[0]), np.minimum(x[1], 1.0 - x[1]))


# The 3D radial obstacle (problems/ex9-3d.toml): f = 0, u >= psi, Dirichlet data u = 1/(2r).
# Also imported by the dolfinx peer benchmark (benches/dolfinx/ex9_3d.py).
def r_3d(x):
    return np.sqrt(x[0] ** 2 + x[1] ** 2 + x[2] ** 2)


def psi_ex9_3d(x):
    """psi = sqrt(1 - r^2) for r <= 1, -1 beyond."""
    r = r_3d(x)
    return np.where(r <= 1.0, np.sqrt(np.maximum(1.0 - r ** 2, 0.0)), -1.0)


def g_ex9_3d(x):
    """1/(2r), and 0 at the origin (an interior vertex: never a Dirichlet value)."""
    r = r_3d(x)
    return np.where(r > 0.0, 0.5 / np.maximum(r, 1e-300), 0.0)


R0_EX9_3D = 1.0 / np.sqrt(2.0)  # the radius of the contact ball


def u_exact_ex9_3d(x):
    """The exact solution: psi on the contact ball r <= R0, 1/(2r) outside it."""
    r = r_3d(x)
    return np.where(r <= R0_EX9_3D, psi_ex9_3d(x), 0.5 / np.maximum(r, 1e-300))


# The 3D Signorini problem (problems/signorini-3d.toml): two materials by cell tag (1: y < 1/2,
# 2: y > 1/2), u = 0 on the faces tagged 12 and 15, flux on 11 and 14, u <= 0 on 10 (x = 0)
SIGNORINI_A = {1: [[100.0, 0.0, 0.0], [0.0, 100.0, 30.0], [0.0, 30.0, 20.0]],
               2: [[1.0, 0.0, 0.0], [0.0, 2.0, 0.5], [0.0, 0.5, 1.0]]}


def _sig_parts(x):
    y = x[1]
    return dict(P=-y * (y - 0.5) ** 2, dP=-(3 * y ** 2 - 2 * y + 0.25), d2P=2 - 6 * y,
                G=(1 - y) * (y - 0.5) ** 2, dG=-3 * y ** 2 + 4 * y - 1.25, d2G=4 - 6 * y)


def f_sig_1(x):  # cells tagged 1
    p, h = _sig_parts(x), np.cos(np.pi * x[0])
    w, dw = np.cos(0.5 * np.pi * x[2]), -0.5 * np.pi * np.sin(0.5 * np.pi * x[2])
    return 105 * np.pi ** 2 * p["P"] * h * w - 100 * p["d2P"] * h * w - 60 * p["dP"] * h * dw


def f_sig_2(x):  # cells tagged 2
    p, g = _sig_parts(x), np.sin(0.5 * np.pi * x[0]) ** 2
    w, dw = np.cos(0.5 * np.pi * x[2]), -0.5 * np.pi * np.sin(0.5 * np.pi * x[2])
    return -(0.5 * np.pi ** 2 * np.cos(np.pi * x[0]) * p["G"] * w + 2 * g * p["d2G"] * w
             - 0.25 * np.pi ** 2 * g * p["G"] * w + g * p["dG"] * dw)


def flux_sig(ufl, x):
    """The Neumann flux of signorini-3d.toml as a ufl expression of the coordinates x."""
    y = x[1]
    dP = -(3 * y ** 2 - 2 * y + 0.25)
    dG = -3 * y ** 2 + 4 * y - 1.25
    h, g = ufl.cos(ufl.pi * x[0]), ufl.sin(0.5 * ufl.pi * x[0]) ** 2
    inner = ufl.conditional(ufl.lt(y, 0.5), -30 * dP * h, -0.5 * g * dG)
    return ufl.conditional(ufl.lt(x[2], 1e-9), inner, 0.0)


# ---------------------------------------------------------------------------

def read_mesh(path, gdim=2):
    import gmsh
    from mpi4py import MPI
    from dolfinx.io import gmshio

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("reference")
        gmsh.merge(path)
        mesh, cell_tags, facet_tags = gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=gdim)
    finally:
        gmsh.finalize()
    return mesh, cell_tags, facet_tags


def solve_case(case, mesh_path, outdir, lu_solver="petsc", test2_f="average"):
    import ufl
    from dolfinx import fem
    from dolfinx.fem import petsc as fpetsc
    from petsc4py import PETSc

    test, k, C = parse_case(case)
    gdim = 3 if test in TESTS_3D else 2
    t0 = time.perf_counter()
    mesh, cell_tags, facet_tags = read_mesh(mesh_path, gdim)
    tdim = mesh.topology.dim
    V = fem.FunctionSpace(mesh, ("CG", 1))
    n_cells = mesh.topology.index_map(tdim).size_local
    n_vertices = mesh.topology.index_map(0).size_local
    n_dofs = V.dofmap.index_map.size_local
    assert n_dofs == n_vertices

    mesh.topology.create_connectivity(tdim - 1, tdim)

    def dofs_on(tag):
        return fem.locate_dofs_topological(V, tdim - 1, facet_tags.find(tag))

    dir_tags = [12, 15] if test == "signorini3d" else [1]
    dir_dofs = np.unique(np.concatenate([dofs_on(t) for t in dir_tags]))
    if len(dir_dofs) == 0:
        raise SystemExit(f"solve.py: {mesh_path}: no facets with physical tag(s) {dir_tags} (Dirichlet)")
    # Dirichlet values at the vertices: 0 (2D tests), the exact solution (3D radial obstacle)
    g_dir = fem.Function(V)
    if test == "ex9_3d":
        g_dir.interpolate(g_ex9_3d)
    bc = fem.dirichletbc(g_dir, dir_dofs)

    u = ufl.TrialFunction(V)
    v = ufl.TestFunction(V)
    f_h = fem.Function(V)
    if test == "test1":
        f_h.interpolate(f_test1)
        a = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
    elif test == "test2tri":
        Q = fem.FunctionSpace(mesh, ("DG", 0))
        kappa = fem.Function(Q)
        kappa.interpolate(A_test2)  # DG0 interpolation point = cell centroid
        a = kappa * ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
        if test2_f == "average":
            f_h.interpolate(f_test2)
        else:  # "onesided": on each cell, P1 interpolant of the formula of the cell's side
            f_lo, f_up = fem.Function(V), fem.Function(V)
            f_lo.interpolate(f2_lower)
            f_up.interpolate(f2_upper)
            chi = fem.Function(Q)
            chi.interpolate(lambda x: (x[1] < 0.5).astype(np.float64))
            f_h = chi * f_lo + (1.0 - chi) * f_up
    elif test == "ex9_3d":
        a = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx  # f = 0: f_h stays 0
    elif test == "signorini3d":
        # A constant on each tag; f_h on a cell = P1 interpolant of its tag's formula
        dxt = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
        a = sum(ufl.inner(ufl.as_matrix(A_t) * ufl.grad(u), ufl.grad(v)) * dxt(t)
                for t, A_t in SIGNORINI_A.items())
        f_1, f_2 = fem.Function(V), fem.Function(V)
        f_1.interpolate(f_sig_1)
        f_2.interpolate(f_sig_2)
        q2 = {"quadrature_degree": 2}
        # flux: the centroid rule on each boundary triangle (degree 1: one point, the
        # centroid), as gradvi's |sigma| g(x_sigma)/3 at each vertex of the face
        dst = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags, metadata={"quadrature_degree": 1})
        L = (f_1 * v * dxt(1, metadata=q2) + f_2 * v * dxt(2, metadata=q2)
             + flux_sig(ufl, ufl.SpatialCoordinate(mesh)) * v * dst((11, 14)))
    else:
        f_h.x.array[:] = C
        a = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
    if test != "signorini3d":
        # quadrature degree 2 (ufl's default for P1*P1): exact for P1*P1 (and DG0*P1*P1)
        L = f_h * v * ufl.dx(metadata={"quadrature_degree": 2})

    a_form, L_form = fem.form(a), fem.form(L)
    A = fpetsc.assemble_matrix(a_form, bcs=[bc])
    A.assemble()
    b = fpetsc.assemble_vector(L_form)
    fpetsc.apply_lifting(b, [a_form], bcs=[[bc]])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fpetsc.set_bc(b, [bc])

    # Bounds
    INF, NINF = PETSc.INFINITY, PETSc.NINFINITY
    lb_a = np.full(n_dofs, NINF)
    ub_a = np.full(n_dofs, INF)
    is_dir = np.zeros(n_dofs, dtype=bool)
    is_dir[dir_dofs] = True
    if test == "test1":
        g3 = dofs_on(3)
        lb_a[g3] = 0.0
    elif test == "test2tri":
        g3 = dofs_on(3)
        ub_a[g3] = 0.0
    elif test == "ex9_3d":
        xdofs = V.tabulate_dof_coordinates()[:n_dofs]
        lb_a[:] = psi_ex9_3d(xdofs.T)
    elif test == "signorini3d":
        ub_a[dofs_on(10)] = 0.0
    else:
        xdofs = V.tabulate_dof_coordinates()[:n_dofs]
        lb_a[:] = psi_test3(xdofs.T)
    g_a = g_dir.x.array[:n_dofs]
    lb_a[is_dir] = g_a[is_dir]
    ub_a[is_dir] = g_a[is_dir]
    constrained = (~is_dir) & ((lb_a > NINF) | (ub_a < INF))
    n_constrained = int(constrained.sum())

    lb = A.createVecRight()
    ub = A.createVecRight()
    lb.array[:] = lb_a
    ub.array[:] = ub_a

    # Initial guess: 0 projected onto [lb, ub]
    x = A.createVecRight()
    x.array[:] = np.minimum(np.maximum(0.0, lb_a), ub_a)

    def F_fn(_snes, X, Fv):
        A.mult(X, Fv)
        Fv.axpy(-1.0, b)

    def J_fn(_snes, _X, _J, _P):
        return  # A is constant

    Fvec = A.createVecLeft()
    snes = PETSc.SNES().create(mesh.comm)
    prefix = f"ref_{case}_"
    snes.setOptionsPrefix(prefix)
    opts = PETSc.Options()
    opts[prefix + "snes_type"] = "vinewtonrsls"
    opts[prefix + "snes_linesearch_type"] = "basic"
    opts[prefix + "snes_atol"] = 1e-12
    opts[prefix + "snes_rtol"] = 1e-12
    opts[prefix + "snes_stol"] = 0.0
    opts[prefix + "snes_max_it"] = 1000
    opts[prefix + "snes_max_funcs"] = 100000
    opts[prefix + "ksp_type"] = "preonly"
    opts[prefix + "pc_type"] = "lu"
    opts[prefix + "pc_factor_mat_solver_type"] = lu_solver
    snes.setFunction(F_fn, Fvec)
    snes.setJacobian(J_fn, A)
    snes.setVariableBounds(lb, ub)
    snes.setFromOptions()
    t1 = time.perf_counter()
    snes.solve(None, x)
    t2 = time.perf_counter()
    reason = snes.getConvergedReason()
    its = snes.getIterationNumber()
    for key in list(opts.getAll().keys()):
        if key.startswith(prefix):
            opts.delValue(key)

    # Diagnostics
    xa = x.array.copy()
    F_fn(None, x, Fvec)
    Fa = Fvec.array.copy()
    gaps = []
    has_lb = constrained & (lb_a > NINF)
    has_ub = constrained & (ub_a < INF)
    if has_lb.any():
        gaps.append((xa - lb_a)[has_lb].min())
    if has_ub.any():
        gaps.append((ub_a - xa)[has_ub].min())
    min_gap = float(min(gaps)) if gaps else float("nan")
    inside = (xa > lb_a) & (xa < ub_a)
    res_inf = float(np.abs(Fa[inside]).max()) if inside.any() else 0.0
    # sign of the multiplier on the active set (F >= 0 at lower, <= 0 at upper bounds)
    at_lb = (~is_dir) & (xa <= lb_a)
    at_ub = (~is_dir) & (xa >= ub_a)
    wrong_sign = max(float((-Fa[at_lb]).max()) if at_lb.any() else 0.0,
                     float(Fa[at_ub].max()) if at_ub.any() else 0.0, 0.0)
    dir_err = float(np.abs(xa[is_dir] - g_a[is_dir]).max())

    # Nodal output, rows in gmsh node-tag order
    os.makedirs(outdir, exist_ok=True)
    geom_dofmap = mesh.geometry.dofmap
    node_to_dof = np.full(mesh.geometry.x.shape[0], -1, dtype=np.int64)
    for c in range(n_cells):
        node_to_dof[geom_dofmap.links(c)] = V.dofmap.cell_dofs(c)
    order = np.argsort(np.asarray(mesh.geometry.input_global_indices))
    dofs_in_order = node_to_dof[order]
    assert (dofs_in_order >= 0).all()
    xdofs = V.tabulate_dof_coordinates()
    nodal_path = os.path.join(outdir, f"nodal_{case}.csv")
    with open(nodal_path, "w") as fh:
        fh.write("x,y,z,u\n" if gdim == 3 else "x,y,u\n")
        for d in dofs_in_order:
            coords = ",".join(f"{xdofs[d, i]:.17g}" for i in range(gdim))
            fh.write(f"{coords},{xa[d]:.17g}\n")

    extra = ""
    if test == "test2tri":
        ue = u_exact_test2(xdofs[:n_dofs].T)
        extra = f" max|u-u_exact| at vertices={np.abs(xa - ue).max():.3e}"

    row = {
        "case": case,
        "test": {"test1": "test1", "test2tri": "test2", "test3": "test3", **TESTS_3D}[test],
        "mesh": os.path.basename(mesh_path),
        "C": "" if C is None else f"{C:g}",
        "n_cells": n_cells,
        "n_vertices": n_vertices,
        "n_constrained": n_constrained,
        "snes_iterations": its,
        "snes_reason": reason,
        "time_setup_s": f"{t1 - t0:.4f}",
        "time_solve_s": f"{t2 - t1:.4f}",
        "min_bound_gap": f"{min_gap:.6e}",
        "residual_inf": f"{res_inf:.6e}",
    }
    log(f"{case}: mesh={row['mesh']} cells={n_cells} vertices={n_vertices} constrained={n_constrained} "
        f"active={int(at_lb.sum() + at_ub.sum())} SNES its={its} reason={reason} "
        f"setup={t1 - t0:.3f}s solve={t2 - t1:.3f}s min_gap={min_gap:.3e} res_inf={res_inf:.3e} "
        f"multiplier_wrong_sign={wrong_sign:.1e} dirichlet_err={dir_err:.1e}{extra}")
    snes.destroy()
    A.destroy()
    b.destroy()
    return row, reason > 0


def update_summary(outdir, rows, name="reference_summary.csv"):
    path = os.path.join(outdir, name)
    existing = []
    if os.path.exists(path):
        with open(path, newline="") as fh:
            rd = csv.reader(fh)
            header = next(rd, None)
            if header == SUMMARY_HEADER:
                existing = [dict(zip(header, r)) for r in rd if r]
    new_cases = {r["case"] for r in rows}
    merged = [r for r in existing if r["case"] not in new_cases] + rows
    with open(path, "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=SUMMARY_HEADER, lineterminator="\n")
        wr.writeheader()
        for r in merged:
            wr.writerow(r)
    return path


def default_mesh(case):
    test, k, _ = parse_case(case)
    sub = "3d" if test in TESTS_3D else ""
    return os.path.join(MESHDIR, sub, f"{test}_{k}.msh")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--case", help="one case, e.g. test1_2, test2tri_3, test3_2_C10")
    g.add_argument("--all", action="store_true", help="every case on every mesh (24 solves)")
    g.add_argument("--coarse", action="store_true", help="coarsest mesh of each test, every C for test3")
    ap.add_argument("--mesh", help="mesh file for --case (default meshes/<test>_<k>.msh)")
    ap.add_argument("--outdir", default=os.path.join(HERE, "out"), help="output directory (default reference/out)")
    ap.add_argument("--lu", default="petsc", help="PETSc LU package: petsc (default), mumps, superlu")
    ap.add_argument("--test2-f", choices=["average", "onesided"], default="onesided",
                    help="load of test2 near y=1/2: 'average' (default; P1 interpolant of f, vertices on "
                         "y=1/2 get the mean of the two one-sided values) or 'onesided' (on each cell "
                         "the P1 interpolant of the formula of the cell's side; much more accurate)")
    args = ap.parse_args()

    from mpi4py import MPI
    if MPI.COMM_WORLD.size != 1:
        raise SystemExit("solve.py: run serially (the CSV output assumes one process)")
    import dolfinx
    if not dolfinx.__version__.startswith("0.5."):
        log(f"warning: written for dolfinx 0.5.x, found {dolfinx.__version__}")

    if args.case:
        parse_case(args.case)
        jobs = [(args.case, args.mesh or default_mesh(args.case))]
    else:
        if args.mesh:
            raise SystemExit("solve.py: --mesh only goes with --case")
        cases = ALL_CASES + ALL_CASES_3D if args.all else COARSE_CASES + COARSE_CASES_3D
        jobs = [(c, default_mesh(c)) for c in cases]
    for _, m in jobs:
        if not os.path.exists(m):
            raise SystemExit(f"solve.py: mesh file {m} not found (run 'bash meshes/generate.sh')")

    t_start = time.perf_counter()
    rows, failed = [], []
    for i, (case, mesh_path) in enumerate(jobs, 1):
        log(f"({i}/{len(jobs)}) {case} on {os.path.relpath(mesh_path, ROOT)}")
        row, ok = solve_case(case, mesh_path, args.outdir, args.lu, args.test2_f)
        rows.append(row)
        if not ok:
            failed.append((case, row["snes_reason"]))
            log(f"ERROR: SNES did not converge for {case} (reason {row['snes_reason']})")
    rows_2d = [r for r in rows if r["test"] not in TESTS_3D.values()]
    rows_3d = [r for r in rows if r["test"] in TESTS_3D.values()]
    for part, name in ((rows_2d, "reference_summary.csv"), (rows_3d, SUMMARY_3D)):
        if part:
            log(f"summary written to {update_summary(args.outdir, part, name)}")
    log(f"total time {time.perf_counter() - t_start:.2f}s for {len(jobs)} case(s)")
    if failed:
        log("FAILED (SNES not converged): " + ", ".join(f"{c} (reason {r})" for c, r in failed))
        sys.exit(1)


if __name__ == "__main__":
    main()
