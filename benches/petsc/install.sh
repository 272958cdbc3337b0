#!/usr/bin/env bash
# Installs what benches/petsc/{build,run_ex9}.sh need, from Debian, unless all is present:
# PETSc headers/library with pkg-config (petsc-dev), the PETSc examples (ex9.c, in
# libpetsc<X.Y>-dev-examples), mpicc and mpiexec (Open MPI, pulled in by petsc-dev), cc,
# /usr/bin/time.
set -euo pipefail
ex9_src() {  # where Debian puts ex9.c for the installed PETSc version
  local v
  v=$(pkg-config --modversion PETSc 2>/dev/null | cut -d. -f1,2) || return 1
  echo "/usr/share/petsc/$v/share/petsc/examples/src/snes/tutorials/ex9.c"
}
have_all() {
  pkg-config --exists PETSc 2>/dev/null && command -v mpicc >/dev/null 2>&1 &&
    command -v mpiexec >/dev/null 2>&1 &&
    command -v cc >/dev/null 2>&1 && [ -x /usr/bin/time ] && [ -f "$(ex9_src)" ]
}
have_all && exit 0
SUDO=""
if [ "$(id -u)" != 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO=sudo; else
    echo "benches/petsc/install.sh: need root or sudo to apt-get install petsc-dev and the PETSc examples" >&2
    exit 1
  fi
fi
if ! command -v apt-get >/dev/null 2>&1; then
  echo "benches/petsc/install.sh: apt-get not found; install PETSc (with pkg-config file), its examples, mpicc and GNU time by hand" >&2
  exit 1
fi
apt_install() {
  echo "installing $* with apt-get ..." >&2
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "$@" >/dev/null
}
$SUDO apt-get update -qq
# 1) PETSc itself (+ Open MPI's mpicc), pkg-config, a C compiler, GNU time
apt_install petsc-dev pkg-config gcc time
# 2) the examples package matching the installed PETSc version (3.18 on bookworm)
v=$(pkg-config --modversion PETSc | cut -d. -f1,2)
[ -f "$(ex9_src)" ] || apt_install "libpetsc$v-dev-examples"
have_all || { echo "benches/petsc/install.sh: still missing something after apt-get (ex9.c expected at $(ex9_src))" >&2; exit 1; }
echo "PETSc $(pkg-config --modversion PETSc), ex9.c at $(ex9_src)" >&2
