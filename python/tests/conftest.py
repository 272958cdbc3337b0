"""Shared fixtures: the repository root, the command-line binary, meshes and problems used by
several tests."""
import os
from pathlib import Path

import numpy as np
import pytest

import gradvi

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


def cli_binary():
    """The `gradvi` binary: $GRADVI_BIN, else target/release/gradvi (built by `make build`,
    `make replicate-quick`), else None."""
    p = os.environ.get("GRADVI_BIN") or str(ROOT / "target" / "release" / "gradvi")
    return p if Path(p).is_file() and os.access(p, os.X_OK) else None


@pytest.fixture(scope="session")
def test3_mesh() -> gradvi.Mesh:
    return gradvi.Mesh.read(ROOT / "meshes" / "test3_1.msh")


def psi(x, y):
    """The obstacle of the paper's Test 3."""
    return -np.minimum.reduce([x, 1 - x, y, 1 - y])


def make_test3(c: float) -> gradvi.Problem:
    """Test 3 built in Python from a constant and a vectorised callable."""
    return gradvi.Problem(source=c, obstacle=psi, side="lower", name=f"test3 C={c}")


# Bueler's radial obstacle problem (PETSc snes/tutorials/ex9.c) on (-2, 2)^2.
EX9_A = 0.697965148223374
EX9_AA = EX9_A**2 / np.sqrt(1 - EX9_A**2)
EX9_B = EX9_AA * np.log(2)


def ex9_psi(x, y):
    r2 = x * x + y * y
    return np.where(r2 <= 1, np.sqrt(np.maximum(1 - r2, 0.0)), -1.0)


def ex9_exact(x, y):
    r = np.sqrt(x * x + y * y)
    outer = -EX9_AA * np.log(np.where(r > 0, r, 1.0)) + EX9_B
    return np.where(r <= EX9_A, ex9_psi(x, y), outer)


def ex9_grad(x, y):
    r2 = x * x + y * y
    inside = np.sqrt(r2) <= EX9_A
    s = np.sqrt(np.where(inside, 1 - r2, 1.0))
    q = np.where(r2 > 0, r2, 1.0)
    return np.where(inside, -x / s, -EX9_AA * x / q), np.where(inside, -y / s, -EX9_AA * y / q)


def make_ex9() -> gradvi.Problem:
    return gradvi.Problem(
        source=0.0,
        obstacle=ex9_psi,
        side="lower",
        dirichlet=ex9_exact,
        exact=ex9_exact,
        exact_grad=ex9_grad,
        name="ex9",
    )
