#!/usr/bin/python3
"""dolfinx 0.5 peer of gradvi's 3D radial obstacle benchmark (problems/ex9-3d.toml).

Run with Debian's /usr/bin/python3 (python3-dolfinx 0.5.2), alone or under mpiexec:

  /usr/bin/python3 benches/dolfinx/ex9_3d.py --n 64 --pc gamg
  mpiexec -n 2 /usr/bin/python3 benches/dolfinx/ex9_3d.py --n 64 --pc hypre --linear

The mesh: dolfinx's create_box of (-2,2)^3 with n^3 cubes, each cut into 6 tetrahedra around
its main diagonal from (x_i, y_j, z_k) to (x_{i+1}, y_{j+1}, z_{k+1}): the same tetrahedra as
gradvi's Kuhn generator (src/mesh3d/generate/kuhn.rs, 6n^3 cells, (n+1)^3 vertices), so both
codes solve the same discrete problem: P1 stiffness matrix, f = 0, Dirichlet values
u = 1/(2r) at the boundary vertices (identity rows), lower bound psi(x_v) at every vertex,
psi = sqrt(1 - r^2) for r <= 1 and -1 beyond.

The solve: PETSc SNES vinewtonrsls (reduced-space active-set Newton, basic line search) on
F(u) = A u - b with the bounds, from u0 = max(0, psi) (Dirichlet values on the boundary), with
CG preconditioned by GAMG or hypre BoomerAMG (--pc) to the relative residual --ksp-rtol on each
Newton step, stopped at ||F_reduced|| <= --snes-rtol ||F(u0)||. With --linear: the same matrix
and right-hand side without the bounds, one KSP solve (the same CG, preconditioner and
tolerance) from u = 0: the linear variant for the cost ratio R.

Prints one JSON line on stdout (rank 0): n, processes, unknowns, cells, setup_s (mesh, forms,
assembly, bounds), solve_s (SNES or KSP solve), newton, ksp (Krylov iterations, all steps),
reason, err_max / err_mean (|u - u_exact| at the vertices), active (vertices at the bound),
peak_mib (the sum over the ranks of each rank's peak resident set, getrusage ru_maxrss).
--write-u FILE (one process only) writes u at the vertices as little-endian float64 in the
order i + (n+1) (j + (n+1) k) of the vertex (x_i, y_j, z_k), for a comparison with gradvi.
"""
import argparse
import json
import resource
import sys
import time
from pathlib import Path

T_START = time.perf_counter()

import numpy as np  # noqa: E402
from mpi4py import MPI  # noqa: E402
from petsc4py import PETSc  # noqa: E402

# psi, the Dirichlet data 1/(2r) and the exact solution: the reference solver's formulas
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from reference.solve import g_ex9_3d as dirichlet_value  # noqa: E402
from reference.solve import psi_ex9_3d as psi  # noqa: E402
from reference.solve import u_exact_ex9_3d as exact  # noqa: E402


def options(prefix, args):
    """The PETSc options of the solve, under `prefix`."""
    o = PETSc.Options()
    o[prefix + "ksp_type"] = "cg"
    o[prefix + "ksp_rtol"] = args.ksp_rtol
    o[prefix + "ksp_atol"] = 0.0
    o[prefix + "pc_type"] = args.pc
    if args.pc == "hypre":
        o[prefix + "pc_hypre_type"] = "boomeramg"
    if not args.linear:
        o[prefix + "snes_type"] = "vinewtonrsls"
        o[prefix + "snes_linesearch_type"] = "basic"
        o[prefix + "snes_rtol"] = args.snes_rtol
        o[prefix + "snes_atol"] = 0.0
        o[prefix + "snes_stol"] = 0.0
        o[prefix + "snes_max_it"] = 200


def build(n, comm):
    """Mesh, space, assembled A and b (Dirichlet rows), the bounds and the Dirichlet mask."""
    import ufl
    from dolfinx import fem, mesh
    from dolfinx.fem import petsc as fpetsc

    box = [np.array([-2.0, -2.0, -2.0]), np.array([2.0, 2.0, 2.0])]
    msh = mesh.create_box(comm, box, [n, n, n], mesh.CellType.tetrahedron)
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim - 1, tdim)
    V = fem.FunctionSpace(msh, ("CG", 1))
    n_local = V.dofmap.index_map.size_local
    facets = mesh.exterior_facet_indices(msh.topology)
    dir_dofs = fem.locate_dofs_topological(V, tdim - 1, facets)
    g = fem.Function(V)
    g.interpolate(dirichlet_value)
    bc = fem.dirichletbc(g, dir_dofs)
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = fem.form(ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx)
    zero = fem.Constant(msh, PETSc.ScalarType(0.0))
    L = fem.form(zero * v * ufl.dx)  # f = 0
    A = fpetsc.assemble_matrix(a, bcs=[bc])
    A.assemble()
    b = fpetsc.assemble_vector(L)
    fpetsc.apply_lifting(b, [a], bcs=[[bc]])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fpetsc.set_bc(b, [bc])
    xdofs = V.tabulate_dof_coordinates()[:n_local]
    is_dir = np.zeros(n_local, dtype=bool)
    is_dir[dir_dofs[dir_dofs < n_local]] = True
    g_a = g.x.array[:n_local]
    lb_a = psi(xdofs.T)
    lb_a[is_dir] = g_a[is_dir]
    ub_a = np.full(n_local, PETSc.INFINITY)
    ub_a[is_dir] = g_a[is_dir]
    cells = msh.topology.index_map(tdim).size_local
    return A, b, xdofs, lb_a, ub_a, is_dir, cells


def solve_obstacle(A, b, lb_a, ub_a, args, comm):
    """SNES vinewtonrsls; (solution array, Newton steps, Krylov iterations, reason)."""
    x = A.createVecRight()
    x.array[:] = np.minimum(np.maximum(0.0, lb_a), ub_a)
    lb, ub = A.createVecRight(), A.createVecRight()
    lb.array[:], ub.array[:] = lb_a, ub_a

    def residual(_snes, X, F):
        A.mult(X, F)
        F.axpy(-1.0, b)

    def jacobian(_snes, _X, _J, _P):
        return  # A is constant

    snes = PETSc.SNES().create(comm)
    snes.setOptionsPrefix("peer_")
    options("peer_", args)
    snes.setFunction(residual, A.createVecLeft())
    snes.setJacobian(jacobian, A)
    snes.setVariableBounds(lb, ub)
    snes.setFromOptions()
    if args.pc == "gamg":
        # the reduced systems of vinewtonrsls change size with the active set, and GAMG (PETSc
        # 3.18) fails on a size change ("Cannot change local size of Amat after use"), even
        # after KSPReset: between Newton steps (in the monitor) the preconditioner's type is set
        # to none and back, which destroys GAMG's hierarchy, and the next step builds a new one
        # from scratch on its reduced operator, as hypre rebuilds its own at each step
        def fresh_pc(s, _its, _norm):
            pc = s.getKSP().getPC()
            pc.setType("none")  # destroys GAMG's hierarchy
            pc.setType("gamg")
            pc.setFromOptions()

        snes.setMonitor(fresh_pc)
    snes.solve(None, x)
    out = (x.array.copy(), snes.getIterationNumber(), snes.getLinearSolveIterations(),
           snes.getConvergedReason())
    snes.destroy()
    return out


def solve_linear(A, b, args, comm):
    """One KSP solve of A u = b from u = 0; (solution array, 1, Krylov iterations, reason)."""
    x = A.createVecRight()
    x.set(0.0)
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix("peer_")
    options("peer_", args)
    ksp.setOperators(A)
    ksp.setFromOptions()
    ksp.solve(b, x)
    out = (x.array.copy(), 1, ksp.getIterationNumber(), ksp.getConvergedReason())
    ksp.destroy()
    return out


def write_u(path, n, xdofs, u):
    """u at the vertices in the order i + (n+1) (j + (n+1) k), little-endian float64."""
    ijk = np.rint((xdofs + 2.0) * (n / 4.0)).astype(np.int64)
    index = ijk[:, 0] + (n + 1) * (ijk[:, 1] + (n + 1) * ijk[:, 2])
    out = np.empty((n + 1) ** 3)
    out[index] = u
    out.astype("<f8").tofile(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, required=True, help="cubes per side (6 n^3 tetrahedra)")
    ap.add_argument("--pc", choices=["gamg", "hypre"], default="gamg")
    ap.add_argument("--linear", action="store_true", help="the linear variant: no bounds, one KSP solve")
    ap.add_argument("--ksp-rtol", type=float, default=1e-10)
    ap.add_argument("--snes-rtol", type=float, default=1e-10)
    ap.add_argument("--write-u", help="u at the vertices, float64 (one process only)")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    if args.n < 1:
        raise SystemExit("ex9_3d.py: --n must be at least 1")
    if args.write_u and comm.size != 1:
        raise SystemExit("ex9_3d.py: --write-u needs one process")
    t0 = time.perf_counter()
    A, b, xdofs, lb_a, ub_a, is_dir, cells = build(args.n, comm)
    t1 = time.perf_counter()
    if args.linear:
        u, newton, ksp_its, reason = solve_linear(A, b, args, comm)
    else:
        u, newton, ksp_its, reason = solve_obstacle(A, b, lb_a, ub_a, args, comm)
    t2 = time.perf_counter()
    if reason <= 0:
        print(f"ex9_3d.py: n = {args.n}: the solve did not converge (reason {reason})", file=sys.stderr)
        sys.exit(1)
    err = np.abs(u - exact(xdofs.T))
    active = int(((~is_dir) & (u <= lb_a)).sum())
    if args.write_u:
        write_u(args.write_u, args.n, xdofs, u)
    A.destroy()
    b.destroy()
    sums = comm.allreduce(np.array([err.sum(), float(len(err)), float(active)]), op=MPI.SUM)
    err_max = comm.allreduce(float(err.max()) if len(err) else 0.0, op=MPI.MAX)
    cells = comm.allreduce(cells, op=MPI.SUM)
    peak_kib = comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, op=MPI.SUM)
    if comm.rank == 0:
        print(json.dumps({
            "n": args.n, "processes": comm.size, "pc": args.pc, "linear": args.linear,
            "unknowns": int(sums[1]), "cells": cells,
            "import_s": t0 - T_START, "setup_s": t1 - t0, "solve_s": t2 - t1,
            "newton": int(newton), "ksp": int(ksp_its), "reason": int(reason),
            "err_max": err_max, "err_mean": float(sums[0] / sums[1]), "active": int(sums[2]),
            "peak_mib": peak_kib / 1024.0,
        }), flush=True)


if __name__ == "__main__":
    main()
